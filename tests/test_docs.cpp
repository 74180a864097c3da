// The documentation tells the truth about the tree: every document is reachable from the README,
// every benchmark chart is shown in docs/benchmarks.md and was made from a committed tree (its
// metadata names a commit without "-dirty"), and the architecture notes do not call what exists
// "later".
#include <doctest/doctest.h>

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

namespace fs = std::filesystem;

namespace {
const fs::path kRoot = STOKESIAN_SOURCE_DIR;

std::string read_text(const fs::path& p) {
  std::ifstream in(p);
  std::ostringstream o;
  o << in.rdbuf();
  return o.str();
}
}  // namespace

TEST_CASE("every document in docs/ is linked from the README") {
  const std::string readme = read_text(kRoot / "README.md");
  int n = 0;
  for (const auto& e : fs::directory_iterator(kRoot / "docs")) {
    if (e.path().extension() != ".md") continue;
    const std::string link = "(docs/" + e.path().filename().string() + ")";
    CAPTURE(link);
    CHECK(readme.find(link) != std::string::npos);
    ++n;
  }
  CHECK(n >= 10);
}

TEST_CASE("benchmark charts are shown in docs/benchmarks.md and come from committed trees") {
  const std::string doc = read_text(kRoot / "docs/benchmarks.md");
  int charts = 0, results = 0;
  for (const auto& e : fs::directory_iterator(kRoot / "bench/results")) {
    const std::string name = e.path().filename().string();
    CAPTURE(name);
    if (e.path().extension() == ".png") {
      CHECK(doc.find("](../bench/results/" + name + ")") != std::string::npos);  // an embedded image
      ++charts;
    } else if (e.path().extension() == ".json") {
      const std::string text = read_text(e.path());
      const auto at = text.find("\"git\"");
      REQUIRE(at != std::string::npos);
      const std::string line = text.substr(at, text.find('\n', at) - at);
      CAPTURE(line);
      CHECK(line.find("-dirty") == std::string::npos);
      CHECK(line.find("unknown") == std::string::npos);
      ++results;
    }
  }
  CHECK(charts >= 4);
  CHECK(results >= 4);
}

TEST_CASE("docs/ARCHITECTURE.md does not call lubrication or the near field 'later'") {
  std::istringstream in(read_text(kRoot / "docs/ARCHITECTURE.md"));
  std::string line;
  while (std::getline(in, line)) {
    std::string l = line;
    std::transform(l.begin(), l.end(), l.begin(), [](unsigned char c) { return char(std::tolower(c)); });
    if (l.find("lubrication") == std::string::npos) continue;
    CAPTURE(line);
    CHECK(l.find("later") == std::string::npos);
    CHECK(l.find("not yet") == std::string::npos);
  }
}
