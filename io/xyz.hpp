#pragma once
// Extended XYZ (the ASE/OVITO convention): per frame
//   N
//   Lattice="ax ay az bx by bz cx cy cz" pbc="T T T" Properties=species:S:1:pos:R:3:radius:R:1[:velo:R:3
//     :omega:R:3:forces:R:3:torque:R:3] Time=t Step=s
//   M1 x y z a [...]   (N lines)
// Lattice (rows = cell vectors) is written for periodic boxes only (open boxes: pbc="F F F" and
// no Lattice); with Lees-Edwards strain g the second vector is (g Ly, Ly, 0). The optional
// columns are those the frame holds. Species: species_labels(). Numbers are printed with 17
// significant digits, so reading a file back reproduces the doubles exactly.
#include "engine/core/domain.hpp"
#include "engine/core/frame.hpp"
#include "engine/core/types.hpp"

#include <cstdint>
#include <fstream>
#include <optional>
#include <string>
#include <vector>

namespace stokesian::io {

struct XyzFrame {
  std::vector<Vec3> position;
  std::vector<double> radius;          // empty if the file has no radius column
  std::vector<std::string> species;    // empty if the file has no species column
  std::optional<Mat3> lattice;         // rows = cell vectors
  std::optional<double> time;
  std::optional<std::int64_t> step;
};

// Every frame of an extended XYZ file. Columns come from Properties= (pos:R:3 required,
// radius:R:1 and species:S:1 optional); without Properties a line is "species x y z [radius]".
// Errors name the file and the line.
std::vector<XyzFrame> read_xyz(const std::string& path);

// Species labels that tell particles apart in a viewer: "M" (mobile) or "F" (fixed), followed by
// the size class, 1 for the smallest distinct radius, 2 for the next ... ; without the number when
// all radii are equal or there are more than kMaxSizeClasses distinct radii (then the radius
// column alone tells sizes apart).
constexpr std::size_t kMaxSizeClasses = 16;
std::vector<std::string> species_labels(const std::vector<double>& radius, const std::vector<char>& fixed);

// Write one frame (position, radius and the kinematic fields `f` has). species: one label per
// particle, or empty for "M".
void write_xyz_frame(std::ostream& os, const Frame& f, const Domain& domain,
                     const std::vector<std::string>& species = {});

// Streaming export for a run. Each frame reaches the file when it is written (a kill loses none of
// the frames before a checkpoint); flush() also fsyncs. On resume, open with `keep_until_step` to
// drop the frames after the checkpoint and a last frame a kill cut short (the file is rewritten
// atomically without them).
class XyzWriter {
 public:
  XyzWriter(std::string path, Domain domain, std::vector<std::string> species = {},
            std::optional<std::int64_t> keep_until_step = std::nullopt);
  void write(const Frame& f);
  void flush();
  const std::string& path() const { return path_; }

 private:
  std::string path_;
  Domain domain_;
  std::vector<std::string> species_;
  std::ofstream os_;
};

}  // namespace stokesian::io
