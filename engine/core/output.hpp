#pragma once
// What the run loop hands to its outputs, defined here so that the engine depends on no writer:
// io/ implements OutputSink (H5MD trajectory + checkpoint, XYZ export) and the application
// (engine/app/) connects the two.
#include "engine/core/domain.hpp"
#include "engine/core/frame.hpp"
#include "engine/core/state.hpp"

#include <cstddef>
#include <string>
#include <utility>
#include <vector>

namespace stokesian {

// The identity of a resolved model as named choices ("hydrodynamics", "moments", ...), compared
// when a run is resumed. Text form: "name=value;name=value" in a fixed order, one line.
struct ModelKey {
  std::vector<std::pair<std::string, std::string>> entries;
  std::string text() const;
  // Parses text(); entries of unknown names are kept. Empty key for text that is not a key.
  static ModelKey parse(const std::string& text);
  // The key of a model description written by stokesian 0.1.0 (files without a stored key): its
  // structured lines "hydrodynamics: L", "moments: M", "far_field: F", "brownian: yes|no"; the
  // reason lines that follow are ignored. Empty when the text has no such lines.
  static ModelKey from_legacy_description(const std::string& description);
  // The key stored in a file: `text` if it is a key, else the legacy reading of it.
  static ModelKey from_stored(const std::string& text);
  bool empty() const { return entries.empty(); }
  bool operator==(const ModelKey& o) const { return entries == o.entries; }
  bool operator!=(const ModelKey& o) const { return !(*this == o); }
};

// What is fixed for a whole run: stored in the output and checked on resume.
struct RunHeader {
  std::size_t particles = 0;
  Domain domain;             // open -> boundary "none"; periodic -> edges [Lx Ly Lz]
  bool sheared_box = false;  // periodic with a moving Lees-Edwards strain: edges per frame
  std::vector<FieldSpec> particle_fields;  // in file order; "position" first, "radius" included
  std::string scene_toml;    // resolved scene text
  std::string model;         // resolved model description (choices and reasons, for people)
  std::string model_key;     // ModelKey::text() of the resolved model (for resume)
  std::string author = "unknown";
  bool records(const std::string& name) const {
    for (const auto& f : particle_fields)
      if (f.name == name) return true;
    return false;
  }
};

class OutputSink {
 public:
  virtual ~OutputSink() = default;
  virtual void record(const Frame& f) = 0;
  // Make every recorded frame durable, then store `s` as the point a resumed run continues from.
  virtual void checkpoint(const State& s) = 0;
};

}  // namespace stokesian
