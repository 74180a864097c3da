// The include rule of the layered architecture (docs/ARCHITECTURE.md): a source file may include
// only headers of its own layer and of the layers it uses, as declared once in CMakeLists.txt
// (stokesian_layer, written to generated/stokesian/layers.txt) and linked the same way. The
// checker runs on the real tree and, to show that it bites, on a small tree with forbidden
// includes.
#include <doctest/doctest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

namespace fs = std::filesystem;

namespace {

struct Layer {
  std::string name, folder;
  std::vector<std::string> uses;
};

std::vector<Layer> read_layers(const std::string& path) {
  std::ifstream in(path);
  REQUIRE(in.good());
  std::vector<Layer> layers;
  for (std::string line; std::getline(in, line);) {
    std::istringstream ss(line);
    Layer l;
    if (!(ss >> l.name >> l.folder)) continue;
    for (std::string u; ss >> u;) l.uses.push_back(u);
    layers.push_back(l);
  }
  return layers;
}

// The layer whose folder is the longest prefix of `path` (a path relative to the source root).
const Layer* layer_of(const std::vector<Layer>& layers, const std::string& path) {
  const Layer* best = nullptr;
  for (const auto& l : layers)
    if (path.rfind(l.folder + "/", 0) == 0 && (!best || l.folder.size() > best->folder.size())) best = &l;
  return best;
}

struct Violation {
  std::string where;  // file:line
  std::string include, why;
};

std::vector<Violation> check_includes(const fs::path& root, const std::vector<Layer>& layers) {
  static const std::regex include_re(R"(^\s*#\s*include\s*"([^"]+)\")");
  std::vector<Violation> out;
  std::vector<fs::path> files;
  for (const auto& l : layers) {
    if (!fs::exists(root / l.folder)) continue;
    for (const auto& e : fs::recursive_directory_iterator(root / l.folder)) {
      const auto ext = e.path().extension();
      if (e.is_regular_file() && (ext == ".hpp" || ext == ".cpp" || ext == ".h")) files.push_back(e.path());
    }
  }
  std::sort(files.begin(), files.end());
  files.erase(std::unique(files.begin(), files.end()), files.end());
  for (const auto& f : files) {
    const std::string rel = fs::relative(f, root).generic_string();
    const Layer* own = layer_of(layers, rel);
    std::ifstream in(f);
    int lineno = 0;
    for (std::string line; std::getline(in, line);) {
      ++lineno;
      std::smatch m;
      if (!std::regex_search(line, m, include_re)) continue;
      const std::string inc = m[1];
      const std::string where = rel + ":" + std::to_string(lineno);
      if (inc.rfind("stokesian/", 0) == 0) continue;  // generated build information
      const Layer* to = layer_of(layers, inc);
      if (!to) {
        out.push_back({where, inc, "not a header of any layer (include project headers by their path from the root)"});
        continue;
      }
      if (to == own || std::count(own->uses.begin(), own->uses.end(), to->name)) continue;
      out.push_back({where, inc, "layer " + own->name + " may not use layer " + to->name});
    }
  }
  return out;
}

std::string report(const std::vector<Violation>& v) {
  std::string s;
  for (const auto& x : v) s += x.where + ": #include \"" + x.include + "\": " + x.why + "\n";
  return s;
}

}  // namespace

TEST_CASE("layers are declared lowest first and use only lower layers") {
  const auto layers = read_layers(STOKESIAN_LAYERS_FILE);
  REQUIRE(layers.size() >= 7);
  for (std::size_t k = 0; k < layers.size(); ++k)
    for (const auto& u : layers[k].uses) {
      const auto it = std::find_if(layers.begin(), layers.end(), [&](const Layer& l) { return l.name == u; });
      CAPTURE(layers[k].name);
      CAPTURE(u);
      REQUIRE(it != layers.end());
      CHECK(std::size_t(it - layers.begin()) < k);
    }
}

TEST_CASE("every #include of the source tree respects the layers") {
  const auto layers = read_layers(STOKESIAN_LAYERS_FILE);
  const auto violations = check_includes(STOKESIAN_SOURCE_DIR, layers);
  INFO(report(violations));
  CHECK(violations.empty());
}

TEST_CASE("the include check fails on forbidden includes and names them") {
  const auto layers = read_layers(STOKESIAN_LAYERS_FILE);
  const fs::path root = fs::temp_directory_path() / "stokesian_layers_demo";
  fs::remove_all(root);
  for (const char* d : {"engine/core", "engine", "trees", "ewald", "io"}) fs::create_directories(root / d);
  // Upward: the core includes the engine top. Sideways: io includes the solver layer.
  std::ofstream(root / "engine/core/types.hpp") << "#pragma once\n#include \"engine/core/domain.hpp\"\n"
                                                   "#include \"engine/simulation.hpp\"\n";
  std::ofstream(root / "io/h5md.cpp") << "#include \"io/h5md.hpp\"\n#include \"engine/core/frame.hpp\"\n\n"
                                         "#include \"lubrication/near_field.hpp\"\n";
  // Allowed: ewald uses trees and the kernels.
  std::ofstream(root / "ewald/pme.cpp") << "#include \"trees/neighbor_list.hpp\"\n#include \"engine/kernels/far_field.hpp\"\n";
  const auto v = check_includes(root, layers);
  INFO(report(v));
  REQUIRE(v.size() == 2);
  CHECK(v[0].where == "engine/core/types.hpp:3");
  CHECK(v[0].why == "layer core may not use layer engine");
  CHECK(v[1].where == "io/h5md.cpp:4");
  CHECK(v[1].why == "layer io may not use layer lubrication");
  fs::remove_all(root);
}
