#pragma once
// Output data as named fields, so that writers (io/) store any quantity without knowing it.
//
// A per-particle field holds N items of `shape` (scalar {}, vector {3}, tensor {6} ...),
// particle-major; an observable holds one item of its shape per frame. Observers
// (engine/observers.hpp) declare their fields once per run and fill them at every output step.
#include "engine/core/types.hpp"

#include <cstdint>
#include <map>
#include <string>
#include <vector>

namespace stokesian {

// Number of values in one item of this shape (1 for a scalar).
inline int item_size(const std::vector<int>& shape) {
  int k = 1;
  for (int s : shape) k *= s;
  return k;
}

struct FieldSpec {
  std::string name;                     // /particles/all/<name> or /observables/<name>
  std::vector<int> shape;               // of one item: {} scalar, {3}, {6}, {3, 3} ...
  std::vector<std::string> components;  // optional labels of the last axis (H5MD attribute)
  int item_size() const { return stokesian::item_size(shape); }
};

struct Field {
  std::vector<int> shape;      // of one item
  std::vector<double> values;  // items, row-major
};

struct Frame {
  std::int64_t step = 0;
  double time = 0.0;
  double shear_strain = 0.0;  // Lees-Edwards strain of the box at this frame
  std::map<std::string, Field> particles;    // per-particle fields (N items each)
  std::map<std::string, Field> observables;  // per-frame quantities (one item each)

  void set_particles(const std::string& name, const std::vector<Vec3>& v) {
    Field& f = particles[name];
    f.shape = {3};
    f.values.resize(3 * v.size());
    for (std::size_t i = 0; i < v.size(); ++i)
      for (int c = 0; c < 3; ++c) f.values[3 * i + std::size_t(c)] = v[i][c];
  }
  void set_particles(const std::string& name, std::vector<double> v) { particles[name] = Field{{}, std::move(v)}; }
  void set_scalar(const std::string& name, double v) { observables[name] = Field{{}, {v}}; }
  double scalar(const std::string& name) const { return observables.at(name).values.at(0); }
  std::vector<Vec3> vec3s(const std::string& name) const {
    const Field& f = particles.at(name);
    std::vector<Vec3> v(f.values.size() / 3);
    for (std::size_t i = 0; i < v.size(); ++i) v[i] = Vec3(f.values[3 * i], f.values[3 * i + 1], f.values[3 * i + 2]);
    return v;
  }
};

}  // namespace stokesian
