#include "engine/types.hpp"

namespace stokesian {
const char* to_string(Moments m) {
  switch (m) {
    case Moments::F: return "F";
    case Moments::FT: return "FT";
    case Moments::FTS: return "FTS";
  }
  return "?";
}
}  // namespace stokesian
