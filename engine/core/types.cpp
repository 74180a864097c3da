#include "engine/core/types.hpp"

#include "engine/core/names.hpp"

namespace stokesian {
const char* to_string(Moments m) { return name_of(m); }
}  // namespace stokesian
