#pragma once
// Reading an HDF5 file back with the C API for exact comparisons: every dataset and attribute as
// shape + raw bytes, and the differences between two such reads. Used by the kill-and-resume
// tests (tests/kill/kill_trials.cpp, tests/test_sweep_kill.cpp).
#include <hdf5.h>

#include <algorithm>
#include <map>
#include <string>
#include <vector>

namespace stokesian::test {

// Reading back with the HDF5 C API: every dataset and attribute as shape + raw bytes in the
// native form of its type (variable-length strings as their text).
struct Blob {
  std::vector<hsize_t> dims;
  std::string type;  // class and size, to tell types apart
  std::string bytes;
  bool ok = false;
};

inline Blob read_object(hid_t obj, bool attribute) {
  Blob b;
  const hid_t ftype = attribute ? H5Aget_type(obj) : H5Dget_type(obj);
  const hid_t space = attribute ? H5Aget_space(obj) : H5Dget_space(obj);
  if (ftype < 0 || space < 0) return b;
  const int rank = H5Sget_simple_extent_ndims(space);
  b.dims.resize(std::size_t(std::max(rank, 0)));
  if (rank > 0) H5Sget_simple_extent_dims(space, b.dims.data(), nullptr);
  const hssize_t n = H5Sget_simple_extent_npoints(space);
  const H5T_class_t cls = H5Tget_class(ftype);
  b.type = std::to_string(int(cls)) + ":" + std::to_string(H5Tget_size(ftype));
  herr_t rc = 0;
  if (cls == H5T_STRING && H5Tis_variable_str(ftype) > 0) {
    std::vector<char*> s(std::size_t(std::max<hssize_t>(n, 0)));
    const hid_t mt = H5Tcopy(H5T_C_S1);
    H5Tset_size(mt, H5T_VARIABLE);
    rc = attribute ? H5Aread(obj, mt, s.data()) : H5Dread(obj, mt, H5S_ALL, H5S_ALL, H5P_DEFAULT, s.data());
    for (char* p : s) {
      b.bytes += p ? p : "";
      b.bytes += '\0';
    }
    if (rc >= 0) H5Dvlen_reclaim(mt, space, H5P_DEFAULT, s.data());
    H5Tclose(mt);
  } else {
    const hid_t mt = H5Tget_native_type(ftype, H5T_DIR_ASCEND);
    b.bytes.assign(std::size_t(std::max<hssize_t>(n, 0)) * H5Tget_size(mt), '\0');
    rc = attribute ? H5Aread(obj, mt, b.bytes.data()) : H5Dread(obj, mt, H5S_ALL, H5S_ALL, H5P_DEFAULT, b.bytes.data());
    H5Tclose(mt);
  }
  b.ok = rc >= 0;
  H5Sclose(space);
  H5Tclose(ftype);
  return b;
}

// name -> content, for every dataset ("/path") and attribute ("/path@name") reachable by a link.
// Returns false (with `error`) when the file cannot be opened or an object cannot be read.
inline bool read_file(const std::string& path, std::map<std::string, Blob>& out, std::string& error) {
  out.clear();
  const hid_t f = H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  if (f < 0) {
    error = path + ": HDF5 cannot open it";
    return false;
  }
  struct Ctx {
    std::map<std::string, Blob>* out;
    std::string error;
  } ctx{&out, ""};
  auto read_attrs = [](hid_t obj, const std::string& name, Ctx& c) {
    const int na = H5Aget_num_attrs(obj);
    for (int i = 0; i < na; ++i) {
      const hid_t a = H5Aopen_by_idx(obj, ".", H5_INDEX_NAME, H5_ITER_INC, hsize_t(i), H5P_DEFAULT, H5P_DEFAULT);
      if (a < 0) {
        c.error = name + ": attribute " + std::to_string(i) + " cannot be opened";
        continue;
      }
      char an[256] = {0};
      H5Aget_name(a, sizeof an, an);
      Blob b = read_object(a, true);
      if (!b.ok) c.error = name + "@" + an + ": cannot be read";
      (*c.out)[name + "@" + an] = std::move(b);
      H5Aclose(a);
    }
  };
  read_attrs(f, "/", ctx);
  struct Visit {
    static herr_t cb(hid_t g, const char* name, const H5L_info_t*, void* data) {
      auto& c = *static_cast<Ctx*>(data);
      const hid_t o = H5Oopen(g, name, H5P_DEFAULT);
      if (o < 0) {
        c.error = std::string("/") + name + ": cannot be opened";
        return 0;
      }
      H5O_info_t info;
      H5Oget_info2(o, &info, H5O_INFO_BASIC);
      const std::string key = std::string("/") + name;
      if (info.type == H5O_TYPE_DATASET) {
        Blob b = read_object(o, false);
        if (!b.ok) c.error = key + ": cannot be read";
        (*c.out)[key] = std::move(b);
      }
      // Attributes of groups and datasets.
      const int na = H5Aget_num_attrs(o);
      for (int i = 0; i < na; ++i) {
        const hid_t a = H5Aopen_by_idx(o, ".", H5_INDEX_NAME, H5_ITER_INC, hsize_t(i), H5P_DEFAULT, H5P_DEFAULT);
        if (a < 0) continue;
        char an[256] = {0};
        H5Aget_name(a, sizeof an, an);
        Blob b = read_object(a, true);
        if (!b.ok) c.error = key + "@" + an + ": cannot be read";
        (*c.out)[key + "@" + an] = std::move(b);
        H5Aclose(a);
      }
      H5Oclose(o);
      return 0;
    }
  };
  const herr_t rc = H5Lvisit(f, H5_INDEX_NAME, H5_ITER_INC, &Visit::cb, &ctx);
  H5Fclose(f);
  if (rc < 0 && ctx.error.empty()) ctx.error = path + ": visiting its links failed";
  if (!ctx.error.empty()) {
    error = path + ": " + ctx.error;
    return false;
  }
  return true;
}

inline std::string dims_text(const std::vector<hsize_t>& d) {
  std::string s = "(";
  for (std::size_t i = 0; i < d.size(); ++i) s += (i ? "," : "") + std::to_string(d[i]);
  return s + ")";
}

// Differences between `got` and `ref`; with `prefix`, the first dimension of a dataset may be
// shorter than the reference's (a trajectory that has not reached the end yet) and only its rows
// are compared.
inline std::vector<std::string> compare(const std::map<std::string, Blob>& got, const std::map<std::string, Blob>& ref,
                                 bool prefix) {
  std::vector<std::string> diffs;
  // Observables are created with the first committed frame: a trajectory without frames may lack them.
  const auto pos = got.find("/particles/all/position/value");
  const bool no_frames = pos == got.end() || pos->second.dims.empty() || pos->second.dims[0] == 0;
  for (const auto& [name, r] : ref) {
    const auto it = got.find(name);
    if (it == got.end()) {
      if (!(prefix && no_frames && name.rfind("/observables/", 0) == 0)) diffs.push_back(name + ": missing");
      continue;
    }
    const Blob& g = it->second;
    if (g.type != r.type) {
      diffs.push_back(name + ": type " + g.type + " instead of " + r.type);
      continue;
    }
    const bool shorter = prefix && !r.dims.empty() && g.dims.size() == r.dims.size() && g.dims[0] <= r.dims[0] &&
                         std::equal(g.dims.begin() + 1, g.dims.end(), r.dims.begin() + 1);
    if (g.dims != r.dims && !shorter) {
      diffs.push_back(name + ": shape " + dims_text(g.dims) + " instead of " + dims_text(r.dims));
      continue;
    }
    if (r.bytes.compare(0, g.bytes.size(), g.bytes) != 0 || (!shorter && g.bytes.size() != r.bytes.size())) {
      // First differing element, for the report.
      std::size_t at = 0;
      while (at < g.bytes.size() && at < r.bytes.size() && g.bytes[at] == r.bytes[at]) ++at;
      diffs.push_back(name + ": values differ (first differing byte " + std::to_string(at) + " of " +
                      std::to_string(r.bytes.size()) + ")");
    }
  }
  for (const auto& [name, g] : got)
    if (!ref.count(name)) diffs.push_back(name + ": not in the uninterrupted run");
  return diffs;
}

}  // namespace stokesian::test
