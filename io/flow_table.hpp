#pragma once
// Flow fields exported by a fluid solver ([flow] kind = "tabulated"; docs/channels.md).
//
// A plain-text table, one grid node per line: x, y, z, u, v, w (6 columns), or x, y, u, v for a 2D
// field in the x-y plane (4 columns: z = 0, w = 0). Separators: commas, semicolons, spaces or tabs.
// Lines starting with '#' or '%' (COMSOL's header) and a first line of column names are skipped.
// The nodes must form a complete rectilinear grid (every combination of the distinct x, y and z
// values exactly once, in any order); a velocity of NaN marks a node without data (inside a solid).
// Units: lengths in a, velocities in a per time unit (convert before export).
//
// Or a legacy VTK file (first line "# vtk DataFile Version ..."; VTK User's Guide, "VTK File
// Formats"), ASCII or BINARY (big-endian), DATASET STRUCTURED_POINTS (DIMENSIONS, ORIGIN, SPACING)
// or RECTILINEAR_GRID (X/Y/Z_COORDINATES), with the velocity as POINT_DATA: the only 3-component
// array (VECTORS, or a FIELD array), or the one named U, u, velocity or Velocity. Points are ordered
// x fastest, then y, then z, as in FlowGrid. A point whose vtkValidPointMask is 0 (ParaView's
// Resample To Image: outside the solver's mesh) has no data (NaN). Written by ParaView's legacy
// writer after Resample To Image, from any solver's mesh.
#include "engine/core/scene.hpp"

#include <string>

namespace stokesian::io {

// Throws ConfigError naming the file and line on unreadable or incomplete tables.
FlowGrid read_flow_table(const std::string& path);

}  // namespace stokesian::io
