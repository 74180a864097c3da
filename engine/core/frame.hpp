#pragma once
// Output data as named fields, so that writers (io/) store any quantity without knowing it.
//
// A per-particle field holds N items of `shape` (scalar {}, vector {3}, tensor {6} ...),
// particle-major; an observable holds one item of its shape per frame. Observers
// (engine/observers.hpp) declare their fields once per run and fill them at every output step.
// Each field carries its unit (H5MD unit string in the reduced units of docs/units.md, "" for a
// pure number) and whether its values are integers (counts, image indices: stored as integers).
#include "engine/core/types.hpp"

#include <cstdint>
#include <map>
#include <string>
#include <utility>
#include <vector>

namespace stokesian {

// Number of values in one item of this shape (1 for a scalar).
inline int item_size(const std::vector<int>& shape) {
  int k = 1;
  for (int s : shape) k *= s;
  return k;
}

struct FieldSpec {
  FieldSpec() = default;
  FieldSpec(std::string n, std::vector<int> s, std::vector<std::string> c = {}, std::string u = "", bool i = false)
      : name(std::move(n)), shape(std::move(s)), components(std::move(c)), unit(std::move(u)), integer(i) {}
  std::string name;                     // /particles/all/<name> or /observables/<name>
  std::vector<int> shape;               // of one item: {} scalar, {3}, {6}, {3, 3} ...
  std::vector<std::string> components;  // optional labels of the last axis (H5MD attribute)
  std::string unit;                     // H5MD unit string, e.g. "a", "kT a-1"; "" = dimensionless
  bool integer = false;                 // values are integers (stored as an integer dataset)
  int item_size() const { return stokesian::item_size(shape); }
};

// H5MD unit strings of the reduced units (docs/units.md): symbols a (reference radius),
// mu (reference viscosity), kT (reference thermal energy), factors separated by spaces.
namespace units {
inline const std::string length = "a";
inline const std::string area = "a+2";
inline const std::string time = "mu a+3 kT-1";
inline const std::string velocity = "kT mu-1 a-2";
inline const std::string angular_velocity = "kT mu-1 a-3";
inline const std::string force = "kT a-1";
inline const std::string energy = "kT";  // also torque and stresslet
inline const std::string stress = "kT a-3";
}  // namespace units

struct Field {
  Field() = default;
  Field(std::vector<int> s, std::vector<double> v, std::string u = "", bool i = false)
      : shape(std::move(s)), values(std::move(v)), unit(std::move(u)), integer(i) {}
  std::vector<int> shape;      // of one item
  std::vector<double> values;  // items, row-major (integer fields hold exact integers)
  std::string unit;            // as FieldSpec::unit (observables carry it here)
  bool integer = false;
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
  void set_scalar(const std::string& name, double v, std::string unit = "") {
    observables[name] = Field{{}, {v}, std::move(unit), false};
  }
  void set_count(const std::string& name, std::int64_t v) { observables[name] = Field{{}, {double(v)}, "", true}; }
  double scalar(const std::string& name) const { return observables.at(name).values.at(0); }
  std::vector<Vec3> vec3s(const std::string& name) const {
    const Field& f = particles.at(name);
    std::vector<Vec3> v(f.values.size() / 3);
    for (std::size_t i = 0; i < v.size(); ++i) v[i] = Vec3(f.values[3 * i], f.values[3 * i + 1], f.values[3 * i + 2]);
    return v;
  }
};

}  // namespace stokesian
