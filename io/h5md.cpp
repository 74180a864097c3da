#include "io/h5md.hpp"

#include "io/scene_toml.hpp"

#include "stokesian/build_info.hpp"

#include <hdf5.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <fcntl.h>
#include <optional>
#include <sys/stat.h>
#include <unistd.h>

namespace stokesian::io {

// ------------------------------------------------------------------------------------------------
// Durable file operations (POSIX).
namespace detail {

static std::string errno_text() { return std::strerror(errno); }

bool exists(const std::string& path) {
  struct stat st {};
  return ::stat(path.c_str(), &st) == 0;
}

void remove_if_exists(const std::string& path) {
  if (::unlink(path.c_str()) != 0 && errno != ENOENT)
    throw IoError(path + ": cannot remove (" + errno_text() + ")");
}

void fsync_file(const std::string& path) {
  const int fd = ::open(path.c_str(), O_RDONLY);
  if (fd < 0) throw IoError(path + ": cannot open for fsync (" + errno_text() + ")");
  const int rc = ::fsync(fd);
  const std::string err = rc != 0 ? errno_text() : "";
  ::close(fd);
  if (rc != 0) throw IoError(path + ": fsync failed (" + err + ")");
}

void fsync_parent_dir(const std::string& path) {
  const auto slash = path.find_last_of('/');
  const std::string dir = slash == std::string::npos ? "." : (slash == 0 ? "/" : path.substr(0, slash));
  const int fd = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY);
  if (fd < 0) throw IoError(dir + ": cannot open directory for fsync (" + errno_text() + ")");
  ::fsync(fd);  // some file systems refuse fsync on directories; the rename itself is still atomic
  ::close(fd);
}

void durable_rename(const std::string& from, const std::string& to) {
  if (::rename(from.c_str(), to.c_str()) != 0)
    throw IoError("cannot rename " + from + " to " + to + " (" + errno_text() + ")");
  fsync_parent_dir(to);
}

void durable_copy(const std::string& from, const std::string& to) {
  const std::string tmp = to + ".tmp";
  const int in = ::open(from.c_str(), O_RDONLY);
  if (in < 0) throw IoError(from + ": cannot open for copying (" + errno_text() + ")");
  const int out = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  if (out < 0) {
    const std::string err = errno_text();
    ::close(in);
    throw IoError(tmp + ": cannot create (" + err + ")");
  }
  std::vector<char> buf(1 << 20);
  std::string err;
  for (;;) {
    const ssize_t n = ::read(in, buf.data(), buf.size());
    if (n < 0) {
      if (errno == EINTR) continue;
      err = from + ": read failed (" + errno_text() + ")";
      break;
    }
    if (n == 0) break;
    for (ssize_t done = 0; done < n;) {
      const ssize_t w = ::write(out, buf.data() + done, static_cast<size_t>(n - done));
      if (w < 0) {
        if (errno == EINTR) continue;
        err = tmp + ": write failed (" + errno_text() + ")";
        break;
      }
      done += w;
    }
    if (!err.empty()) break;
  }
  if (err.empty() && ::fsync(out) != 0) err = tmp + ": fsync failed (" + errno_text() + ")";
  ::close(in);
  if (::close(out) != 0 && err.empty()) err = tmp + ": close failed (" + errno_text() + ")";
  if (!err.empty()) {
    ::unlink(tmp.c_str());
    throw IoError(err);
  }
  durable_rename(tmp, to);
}

}  // namespace detail

// ------------------------------------------------------------------------------------------------
// Thin HDF5 layer: RAII handles, errors translated to IoError naming the file.
namespace {

void quiet_hdf5() {
  // The library prints its error stack to stderr by default; we report through IoError instead.
  static const bool done = [] {
    H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
    return true;
  }();
  (void)done;
}

// Innermost description on the HDF5 error stack (the most specific reason), then clear it.
std::string hdf5_reason() {
  std::string msg;
  H5Ewalk2(
      H5E_DEFAULT, H5E_WALK_DOWNWARD,
      [](unsigned, const H5E_error2_t* e, void* data) -> herr_t {
        if (e->desc && *e->desc) *static_cast<std::string*>(data) = e->desc;
        return 0;
      },
      &msg);
  H5Eclear2(H5E_DEFAULT);
  return msg;
}

[[noreturn]] void fail(const std::string& file, const std::string& what) {
  const std::string why = hdf5_reason();
  throw IoError(file + ": " + what + (why.empty() ? "" : " (HDF5: " + why + ")"));
}

class H {
 public:
  H() = default;
  H(hid_t id, herr_t (*closer)(hid_t)) : id_(id), close_(closer) {}
  H(H&& o) noexcept : id_(o.id_), close_(o.close_) { o.id_ = -1; }
  H& operator=(H&& o) noexcept {
    if (this != &o) {
      reset();
      id_ = o.id_;
      close_ = o.close_;
      o.id_ = -1;
    }
    return *this;
  }
  H(const H&) = delete;
  H& operator=(const H&) = delete;
  ~H() { reset(); }
  operator hid_t() const { return id_; }
  void reset() {
    if (id_ >= 0 && close_) close_(id_);
    id_ = -1;
  }
  // Close and report failure (for files: this is where buffered data reach the disk).
  void close(const std::string& file) {
    const hid_t id = id_;
    id_ = -1;
    if (id >= 0 && close_(id) < 0) fail(file, "closing failed");
  }

 private:
  hid_t id_ = -1;
  herr_t (*close_)(hid_t) = nullptr;
};

H checked(hid_t id, herr_t (*closer)(hid_t), const std::string& file, const std::string& what) {
  if (id < 0) fail(file, what);
  return H(id, closer);
}
void checked(herr_t rc, const std::string& file, const std::string& what) {
  if (rc < 0) fail(file, what);
}

// Does the (possibly nested) link `path` exist below loc? H5Lexists needs every parent to exist.
bool has_link(hid_t loc, const std::string& path) {
  std::size_t pos = 0;
  while (true) {
    const auto next = path.find('/', pos);
    const std::string prefix = path.substr(0, next);
    if (!prefix.empty() && H5Lexists(loc, prefix.c_str(), H5P_DEFAULT) <= 0) {
      H5Eclear2(H5E_DEFAULT);
      return false;
    }
    if (next == std::string::npos) return true;
    pos = next + 1;
  }
}

H open_file(const std::string& path, unsigned flags) {
  quiet_hdf5();
  if (!detail::exists(path)) throw IoError(path + ": file does not exist");
  // Writers close the file strongly (every object with it), so that data are on disk before fsync.
  // Readers keep the default, which lets them share a file another handle in the process holds.
  H fapl = checked(H5Pcreate(H5P_FILE_ACCESS), H5Pclose, path, "property list");
  if (flags != H5F_ACC_RDONLY) H5Pset_fclose_degree(fapl, H5F_CLOSE_STRONG);
  return checked(H5Fopen(path.c_str(), flags, fapl), H5Fclose, path,
                 flags == H5F_ACC_RDONLY ? "cannot open as HDF5" : "cannot open as HDF5 for writing");
}

H open_group(hid_t loc, const std::string& name, const std::string& file) {
  if (!has_link(loc, name)) throw IoError(file + ": missing group " + name);
  return checked(H5Gopen2(loc, name.c_str(), H5P_DEFAULT), H5Gclose, file, "cannot open group " + name);
}

H open_dataset(hid_t loc, const std::string& name, const std::string& file) {
  if (!has_link(loc, name)) throw IoError(file + ": missing dataset " + name);
  return checked(H5Dopen2(loc, name.c_str(), H5P_DEFAULT), H5Dclose, file, "cannot open dataset " + name);
}

H make_group(hid_t loc, const std::string& name, const std::string& file) {
  H lcpl = checked(H5Pcreate(H5P_LINK_CREATE), H5Pclose, file, "property list");
  H5Pset_create_intermediate_group(lcpl, 1);
  return checked(H5Gcreate2(loc, name.c_str(), lcpl, H5P_DEFAULT, H5P_DEFAULT), H5Gclose, file,
                 "cannot create group " + name);
}

std::vector<hsize_t> dims_of(hid_t dset, const std::string& file) {
  H space = checked(H5Dget_space(dset), H5Sclose, file, "dataspace");
  const int rank = H5Sget_simple_extent_ndims(space);
  if (rank < 0) fail(file, "dataspace rank");
  std::vector<hsize_t> d(static_cast<std::size_t>(rank));
  if (rank > 0) H5Sget_simple_extent_dims(space, d.data(), nullptr);
  return d;
}

// Fixed-length, null-terminated UTF-8 string type (the H5MD convention for string attributes).
H string_type(std::size_t len, const std::string& file, H5T_cset_t cset = H5T_CSET_UTF8) {
  H t = checked(H5Tcopy(H5T_C_S1), H5Tclose, file, "string type");
  H5Tset_size(t, std::max<std::size_t>(len + 1, 1));
  H5Tset_strpad(t, H5T_STR_NULLTERM);
  H5Tset_cset(t, cset);
  return t;
}

void write_attr_ints(hid_t loc, const std::string& name, const std::vector<int>& v, bool scalar,
                     const std::string& file) {
  const hsize_t n = v.size();
  H space = checked(scalar ? H5Screate(H5S_SCALAR) : H5Screate_simple(1, &n, nullptr), H5Sclose, file, "dataspace");
  H a = checked(H5Acreate2(loc, name.c_str(), H5T_STD_I32LE, space, H5P_DEFAULT, H5P_DEFAULT), H5Aclose, file,
                "cannot create attribute " + name);
  checked(H5Awrite(a, H5T_NATIVE_INT, v.data()), file, "cannot write attribute " + name);
}

void write_attr_strings(hid_t loc, const std::string& name, const std::vector<std::string>& v, bool scalar,
                        const std::string& file, H5T_cset_t cset = H5T_CSET_UTF8) {
  std::size_t len = 0;
  for (const auto& s : v) len = std::max(len, s.size());
  H type = string_type(len, file, cset);
  const std::size_t width = len + 1;
  std::vector<char> buf(width * v.size(), '\0');
  for (std::size_t i = 0; i < v.size(); ++i) std::memcpy(buf.data() + i * width, v[i].data(), v[i].size());
  const hsize_t n = v.size();
  H space = checked(scalar ? H5Screate(H5S_SCALAR) : H5Screate_simple(1, &n, nullptr), H5Sclose, file, "dataspace");
  H a = checked(H5Acreate2(loc, name.c_str(), type, space, H5P_DEFAULT, H5P_DEFAULT), H5Aclose, file,
                "cannot create attribute " + name);
  checked(H5Awrite(a, type, buf.data()), file, "cannot write attribute " + name);
}

void write_string_dataset(hid_t loc, const std::string& name, const std::string& s, const std::string& file) {
  H type = string_type(s.size(), file);
  std::vector<char> buf(s.size() + 1, '\0');
  std::memcpy(buf.data(), s.data(), s.size());
  H space = checked(H5Screate(H5S_SCALAR), H5Sclose, file, "dataspace");
  H d = checked(H5Dcreate2(loc, name.c_str(), type, space, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), H5Dclose, file,
                "cannot create dataset " + name);
  checked(H5Dwrite(d, type, H5S_ALL, H5S_ALL, H5P_DEFAULT, buf.data()), file, "cannot write dataset " + name);
}

// Read a string attribute/dataset element by element (fixed or variable length).
std::vector<std::string> read_strings(hid_t obj, bool is_attr, const std::string& what, const std::string& file) {
  H ftype = checked(is_attr ? H5Aget_type(obj) : H5Dget_type(obj), H5Tclose, file, "type of " + what);
  if (H5Tget_class(ftype) != H5T_STRING) throw IoError(file + ": " + what + " is not a string");
  H space = checked(is_attr ? H5Aget_space(obj) : H5Dget_space(obj), H5Sclose, file, "dataspace of " + what);
  const hssize_t n = H5Sget_simple_extent_npoints(space);
  std::vector<std::string> out;
  if (H5Tis_variable_str(ftype) > 0) {
    H mtype = checked(H5Tcopy(H5T_C_S1), H5Tclose, file, "string type");
    H5Tset_size(mtype, H5T_VARIABLE);
    H5Tset_cset(mtype, H5Tget_cset(ftype));  // HDF5 does not convert between ASCII and UTF-8
    std::vector<char*> ptr(static_cast<std::size_t>(n), nullptr);
    const herr_t rc = is_attr ? H5Aread(obj, mtype, ptr.data()) : H5Dread(obj, mtype, H5S_ALL, H5S_ALL, H5P_DEFAULT, ptr.data());
    if (rc < 0) fail(file, "cannot read " + what);
    for (char* p : ptr) out.emplace_back(p ? p : "");
    H5Dvlen_reclaim(mtype, space, H5P_DEFAULT, ptr.data());
    return out;
  }
  const std::size_t width = H5Tget_size(ftype);
  H mtype = checked(H5Tcopy(H5T_C_S1), H5Tclose, file, "string type");
  H5Tset_size(mtype, width);
  H5Tset_strpad(mtype, H5T_STR_NULLPAD);
  H5Tset_cset(mtype, H5Tget_cset(ftype));
  std::vector<char> buf(width * static_cast<std::size_t>(n) + 1, '\0');
  const herr_t rc = is_attr ? H5Aread(obj, mtype, buf.data()) : H5Dread(obj, mtype, H5S_ALL, H5S_ALL, H5P_DEFAULT, buf.data());
  if (rc < 0) fail(file, "cannot read " + what);
  for (hssize_t i = 0; i < n; ++i) {
    const char* p = buf.data() + static_cast<std::size_t>(i) * width;
    out.emplace_back(p, strnlen(p, width));
  }
  return out;
}

std::string read_string_dataset(hid_t loc, const std::string& name, const std::string& file) {
  H d = open_dataset(loc, name, file);
  auto v = read_strings(d, false, name, file);
  if (v.size() != 1) throw IoError(file + ": dataset " + name + " is not a single string");
  return v[0];
}

H open_attr(hid_t loc, const std::string& name, const std::string& where, const std::string& file) {
  if (H5Aexists(loc, name.c_str()) <= 0) {
    H5Eclear2(H5E_DEFAULT);
    throw IoError(file + ": missing attribute " + name + " on " + where);
  }
  return checked(H5Aopen(loc, name.c_str(), H5P_DEFAULT), H5Aclose, file, "cannot open attribute " + name);
}

std::vector<long long> read_attr_ints(hid_t loc, const std::string& name, const std::string& where,
                                      const std::string& file) {
  H a = open_attr(loc, name, where, file);
  H space = checked(H5Aget_space(a), H5Sclose, file, "dataspace");
  std::vector<long long> v(static_cast<std::size_t>(H5Sget_simple_extent_npoints(space)));
  checked(H5Aread(a, H5T_NATIVE_LLONG, v.data()), file, "cannot read attribute " + name + " on " + where);
  return v;
}

// Read the whole 1-D int64 / double dataset.
template <typename T>
std::vector<T> read_vector(hid_t loc, const std::string& name, hid_t memtype, const std::string& file) {
  H d = open_dataset(loc, name, file);
  const auto dims = dims_of(d, file);
  if (dims.size() != 1) throw IoError(file + ": dataset " + name + " should be one-dimensional");
  std::vector<T> v(dims[0]);
  if (!v.empty()) checked(H5Dread(d, memtype, H5S_ALL, H5S_ALL, H5P_DEFAULT, v.data()), file, "cannot read " + name);
  return v;
}

// A time-dependent H5MD element: group with step [var], time [var], value [var][item...].
// `clock`: an existing element whose step/time this one shares through hard links (H5MD allows
// this for elements sampled together, and requires it for a time-dependent box).
void make_element(hid_t loc, const std::string& name, const std::vector<hsize_t>& item, hid_t clock,
                  const std::string& file, const std::string& unit = "", bool integer = false) {
  H g = make_group(loc, name, file);
  // Chunks of at most about 256 KiB (so the default 1 MiB chunk cache holds several and reading
  // one frame stays cheap) and at most 128 frames (so small systems do not allocate large, mostly
  // empty chunks: every chunk is allocated whole on first write).
  hsize_t item_size = 8;
  for (hsize_t d : item) item_size *= d;
  const hsize_t chunk_frames = std::clamp<hsize_t>((256u << 10) / std::max<hsize_t>(item_size, 1), 1, 128);

  auto extensible = [&](const char* dname, hid_t type, std::vector<hsize_t> shape, hsize_t frames_per_chunk) {
    std::vector<hsize_t> cur = shape, max = shape, chunk = shape;
    cur[0] = 0;
    max[0] = H5S_UNLIMITED;
    chunk[0] = frames_per_chunk;
    for (auto& c : chunk) c = std::max<hsize_t>(c, 1);
    H space = checked(H5Screate_simple(static_cast<int>(cur.size()), cur.data(), max.data()), H5Sclose, file, "dataspace");
    H dcpl = checked(H5Pcreate(H5P_DATASET_CREATE), H5Pclose, file, "property list");
    checked(H5Pset_chunk(dcpl, static_cast<int>(chunk.size()), chunk.data()), file, "chunking of " + name);
    H d = checked(H5Dcreate2(g, dname, type, space, H5P_DEFAULT, dcpl, H5P_DEFAULT), H5Dclose, file,
                  "cannot create dataset " + name + "/" + dname);
    return d;
  };
  if (clock >= 0) {
    checked(H5Lcreate_hard(clock, "step", g, "step", H5P_DEFAULT, H5P_DEFAULT), file, "cannot link " + name + "/step");
    checked(H5Lcreate_hard(clock, "time", g, "time", H5P_DEFAULT, H5P_DEFAULT), file, "cannot link " + name + "/time");
  } else {
    extensible("step", H5T_STD_I64LE, {0}, 128);
    H t = extensible("time", H5T_IEEE_F64LE, {0}, 128);
    write_attr_strings(t, "unit", {units::time}, true, file, H5T_CSET_ASCII);  // H5MD: ASCII units
  }
  std::vector<hsize_t> shape{0};
  shape.insert(shape.end(), item.begin(), item.end());
  H v = extensible("value", integer ? H5T_STD_I64LE : H5T_IEEE_F64LE, shape, chunk_frames);
  if (!unit.empty()) write_attr_strings(v, "unit", {unit}, true, file, H5T_CSET_ASCII);
}

// Field values as the dataset's memory type: integer fields as int64 (exact for the counts and
// image indices they hold), others as double. HDF5 converts to the file's type (files of 0.1.0
// store counts as double).
struct Rows {
  std::vector<double> real;
  std::vector<std::int64_t> whole;
  bool integer = false;
  void add(const std::vector<double>& v) {
    if (integer)
      for (double x : v) whole.push_back(static_cast<std::int64_t>(std::llround(x)));
    else
      real.insert(real.end(), v.begin(), v.end());
  }
  hid_t memtype() const { return integer ? H5T_NATIVE_INT64 : H5T_NATIVE_DOUBLE; }
  const void* data() const { return integer ? static_cast<const void*>(whole.data()) : real.data(); }
};

// Append k rows (each of the dataset's item shape) to an extensible dataset.
void append_rows(hid_t loc, const std::string& name, hid_t memtype, const void* data, hsize_t k, const std::string& file) {
  if (k == 0) return;
  H d = open_dataset(loc, name, file);
  auto dims = dims_of(d, file);
  const hsize_t old = dims[0];
  dims[0] = old + k;
  checked(H5Dset_extent(d, dims.data()), file, "cannot extend " + name);
  H fspace = checked(H5Dget_space(d), H5Sclose, file, "dataspace");
  std::vector<hsize_t> start(dims.size(), 0), count = dims;
  start[0] = old;
  count[0] = k;
  checked(H5Sselect_hyperslab(fspace, H5S_SELECT_SET, start.data(), nullptr, count.data(), nullptr), file, "selection");
  H mspace = checked(H5Screate_simple(static_cast<int>(count.size()), count.data(), nullptr), H5Sclose, file, "dataspace");
  checked(H5Dwrite(d, memtype, mspace, fspace, H5P_DEFAULT, data), file, "cannot write " + name);
}

std::vector<hsize_t> item_dims(const std::vector<int>& shape) {
  std::vector<hsize_t> d;
  for (int k : shape) d.push_back(static_cast<hsize_t>(k));
  return d;
}

std::string boundary_name(const Domain& d) { return d.periodic() ? "periodic" : "none"; }

void write_layout(const std::string& path, const RunHeader& h) {
  if (h.particle_fields.empty() || h.particle_fields.front().name != "position")
    throw IoError(path + ": a trajectory's first per-particle field must be position");
  quiet_hdf5();
  H fapl = checked(H5Pcreate(H5P_FILE_ACCESS), H5Pclose, path, "property list");
  H5Pset_fclose_degree(fapl, H5F_CLOSE_STRONG);
  H f = checked(H5Fcreate(path.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, fapl), H5Fclose, path, "cannot create file");
  {
    H g = make_group(f, "h5md", path);
    write_attr_ints(g, "version", {1, 1}, false, path);
    H author = make_group(g, "author", path);
    write_attr_strings(author, "name", {h.author}, true, path);
    H creator = make_group(g, "creator", path);
    write_attr_strings(creator, "name", {"stokesian"}, true, path);
    write_attr_strings(creator, "version", {build::version}, true, path);
    // H5MD units module: the unit attributes below use the reduced units of docs/units.md.
    H um = make_group(g, "modules/units", path);
    write_attr_ints(um, "version", {1, 0}, false, path);
    write_attr_strings(um, "system", {"reduced: a (reference radius), mu (viscosity), kT (thermal energy)"}, true, path);
  }
  {
    H all = make_group(f, "particles/all", path);
    const hsize_t n = h.particles;
    for (const FieldSpec& spec : h.particle_fields) {
      std::vector<hsize_t> item{n};
      for (hsize_t d : item_dims(spec.shape)) item.push_back(d);
      if (spec.name == "position") {
        make_element(all, "position", item, -1, path, spec.unit, spec.integer);
      } else {
        H clock = open_group(all, "position", path);
        make_element(all, spec.name, item, clock, path, spec.unit, spec.integer);
      }
      if (!spec.components.empty()) {
        H g = open_group(all, spec.name, path);
        write_attr_strings(g, "components", spec.components, false, path);
      }
    }

    H box = make_group(all, "box", path);
    write_attr_ints(box, "dimension", {3}, true, path);
    const std::string b = boundary_name(h.domain);
    write_attr_strings(box, "boundary", {b, b, b}, false, path);
    if (h.domain.periodic()) {
      // One matrix per frame whose rows are the edge vectors a = (Lx,0,0), b = (strain Ly, Ly, 0),
      // c = (0,0,Lz): Lees-Edwards boxes change every frame, and readers (MDAnalysis) expect a
      // time-dependent triclinic box. Files of 0.1.0 hold a fixed [3] dataset for unsheared boxes.
      H clock = open_group(all, "position", path);
      make_element(box, "edges", {3, 3}, clock, path, units::length);
    }
  }
  H obs = make_group(f, "observables", path);
  {
    H p = make_group(f, "parameters/stokesian", path);
    write_string_dataset(p, "scene", h.scene_toml, path);
    write_string_dataset(p, "model", h.model, path);
    write_string_dataset(p, "model_key", h.model_key, path);
    write_string_dataset(p, "version", build::version, path);
    write_string_dataset(p, "git", build::git, path);
    write_string_dataset(p, "compiler", build::compiler, path);
    write_string_dataset(p, "build_type", build::build_type, path);
  }
  obs.reset();
  f.close(path);
}

std::int64_t frames_in(hid_t file, const std::string& path) {
  H d = open_dataset(file, "particles/all/position/value", path);
  return static_cast<std::int64_t>(dims_of(d, path)[0]);
}

// Append frames to an open trajectory file; the caller guarantees their order and shapes.
void append_frames(hid_t file, const std::string& path, const RunHeader& h, const std::vector<const Frame*>& fr) {
  if (fr.empty()) return;
  const hsize_t k = fr.size();
  H all = open_group(file, "particles/all", path);
  const hsize_t f0 = static_cast<hsize_t>(frames_in(file, path));
  for (const FieldSpec& spec : h.particle_fields) {
    H d = open_dataset(all, spec.name + "/value", path);
    if (dims_of(d, path)[0] != f0)
      throw IoError(path + ": particles/all/" + spec.name + " has a different frame count than position");
  }
  std::vector<std::int64_t> steps(k);
  std::vector<double> times(k);
  for (hsize_t j = 0; j < k; ++j) {
    steps[j] = fr[j]->step;
    times[j] = fr[j]->time;
  }
  append_rows(all, "position/step", H5T_NATIVE_INT64, steps.data(), k, path);
  append_rows(all, "position/time", H5T_NATIVE_DOUBLE, times.data(), k, path);
  std::vector<double> buf;
  for (const FieldSpec& spec : h.particle_fields) {
    Rows rows;
    rows.integer = spec.integer;
    for (hsize_t j = 0; j < k; ++j) rows.add(fr[j]->particles.at(spec.name).values);
    append_rows(all, spec.name + "/value", rows.memtype(), rows.data(), k, path);
  }
  if (h.domain.periodic() && has_link(all, "box/edges/value")) {
    buf.assign(k * 9, 0.0);
    const Vec3& L = h.domain.box;
    for (hsize_t j = 0; j < k; ++j) {
      double* m = buf.data() + 9 * j;
      m[0] = L.x();
      // An unsheared box keeps the scene's strain (frames of such runs carry the same value).
      m[3] = (h.sheared_box ? fr[j]->shear_strain : h.domain.shear_strain) * L.y();
      m[4] = L.y();
      m[8] = L.z();
    }
    append_rows(all, "box/edges/value", H5T_NATIVE_DOUBLE, buf.data(), k, path);
  }

  // Observables: each has its own clock, since not every frame needs to carry every observable.
  std::map<std::string, const Field*> names;  // name -> its first field (shape, unit, kind)
  for (const Frame* f : fr)
    for (const auto& [name, field] : f->observables) names.emplace(name, &field);
  H obs = open_group(file, "observables", path);
  for (const auto& [name, first] : names) {
    const std::vector<int>& shape = first->shape;
    const std::vector<hsize_t> item = item_dims(shape);
    if (!has_link(obs, name)) {
      make_element(obs, name, item, -1, path, first->unit, first->integer);
    } else {
      H d = open_dataset(obs, name + "/value", path);
      const auto dims = dims_of(d, path);
      if (std::vector<hsize_t>(dims.begin() + 1, dims.end()) != item)
        throw IoError(path + ": observable " + name + " changes shape");
    }
    std::vector<std::int64_t> st;
    std::vector<double> tm;
    Rows val;
    val.integer = first->integer;
    for (const Frame* f : fr) {
      auto it = f->observables.find(name);
      if (it == f->observables.end()) continue;
      if (it->second.shape != shape || it->second.integer != first->integer)
        throw IoError(path + ": observable " + name + " changes shape or kind");
      val.add(it->second.values);
      st.push_back(f->step);
      tm.push_back(f->time);
    }
    append_rows(obs, name + "/step", H5T_NATIVE_INT64, st.data(), st.size(), path);
    append_rows(obs, name + "/time", H5T_NATIVE_DOUBLE, tm.data(), tm.size(), path);
    append_rows(obs, name + "/value", val.memtype(), val.data(), st.size(), path);
  }
}

// Every time-dependent element below loc (groups holding a `value` dataset), as relative paths.
void collect_elements(hid_t loc, const std::string& prefix, std::vector<std::string>& out, const std::string& file) {
  std::vector<std::string> names;
  H5Literate(
      loc, H5_INDEX_NAME, H5_ITER_INC, nullptr,
      [](hid_t, const char* name, const H5L_info_t*, void* data) -> herr_t {
        static_cast<std::vector<std::string>*>(data)->emplace_back(name);
        return 0;
      },
      &names);
  for (const auto& n : names) {
    H5O_info_t info;
    if (H5Oget_info_by_name(loc, n.c_str(), &info, H5P_DEFAULT) < 0) fail(file, "cannot inspect " + prefix + n);
    if (info.type != H5O_TYPE_GROUP) continue;
    H g = checked(H5Gopen2(loc, n.c_str(), H5P_DEFAULT), H5Gclose, file, "cannot open " + prefix + n);
    if (has_link(g, "value")) out.push_back(prefix + n);
    else collect_elements(g, prefix + n + "/", out, file);
  }
}

// Check one element: step/time/value share the leading extent, steps increase strictly.
std::int64_t check_element(hid_t root, const std::string& el, const std::string& file) {
  H g = open_group(root, el, file);
  const auto steps = read_vector<std::int64_t>(g, "step", H5T_NATIVE_INT64, file);
  H t = open_dataset(g, "time", file);
  H v = open_dataset(g, "value", file);
  const auto td = dims_of(t, file), vd = dims_of(v, file);
  if (td.size() != 1 || td[0] != steps.size() || vd.empty() || vd[0] != steps.size())
    throw IoError(file + ": " + el + ": step, time and value hold different numbers of frames");
  for (std::size_t i = 1; i < steps.size(); ++i)
    if (steps[i] <= steps[i - 1]) throw IoError(file + ": " + el + "/step does not increase at frame " + std::to_string(i));
  return static_cast<std::int64_t>(steps.size());
}

// Shrink every element so that it keeps the frames with step <= last_step.
void truncate_elements(hid_t file, const std::string& path, std::int64_t last_step) {
  std::vector<std::string> els;
  H parts = open_group(file, "particles", path);
  collect_elements(parts, "particles/", els, path);
  H obs = open_group(file, "observables", path);
  collect_elements(obs, "observables/", els, path);
  for (const auto& el : els) {
    H g = open_group(file, el, path);
    const auto steps = read_vector<std::int64_t>(g, "step", H5T_NATIVE_INT64, path);
    const hsize_t keep = static_cast<hsize_t>(std::upper_bound(steps.begin(), steps.end(), last_step) - steps.begin());
    for (const char* ds : {"step", "time", "value"}) {
      H d = open_dataset(g, ds, path);
      auto dims = dims_of(d, path);
      if (dims[0] == keep) continue;  // step/time may be shared links already shrunk
      dims[0] = keep;
      checked(H5Dset_extent(d, dims.data()), path, "cannot shrink " + el + "/" + ds);
    }
  }
}

TrajectoryInfo inspect_open(hid_t f, const std::string& path) {
  TrajectoryInfo info;
  {
    H g = open_group(f, "h5md", path);
    const auto v = read_attr_ints(g, "version", "h5md", path);
    if (v.size() != 2 || v[0] != 1) throw IoError(path + ": unsupported H5MD version");
  }
  H all = open_group(f, "particles/all", path);
  {
    H v = open_dataset(all, "position/value", path);
    const auto d = dims_of(v, path);
    if (d.size() != 3 || d[2] != 3) throw IoError(path + ": particles/all/position/value is not frames x N x 3");
    info.particles = d[1];
  }
  {
    std::vector<std::string> groups;
    collect_elements(all, "", groups, path);  // every element below particles/all, box/edges included
    info.frames = check_element(all, "position", path);
    for (const auto& name : groups) {
      if (name.rfind("box/", 0) == 0) continue;
      const std::int64_t frames = name == "position" ? info.frames : check_element(all, name, path);
      if (frames != info.frames)
        throw IoError(path + ": particles/all/" + name + " holds " + std::to_string(frames) + " frames, position " +
                      std::to_string(info.frames));
      H v = open_dataset(all, name + "/value", path);
      const auto d = dims_of(v, path);
      if (d.size() < 2 || d[1] != info.particles) throw IoError(path + ": particles/all/" + name + "/value has the wrong shape");
      FieldSpec spec{name, {}, {}};
      for (std::size_t k = 2; k < d.size(); ++k) spec.shape.push_back(static_cast<int>(d[k]));
      info.particle_fields.push_back(spec);
    }
    if (!info.records("radius")) throw IoError(path + ": missing group particles/all/radius");
  }
  {
    H box = open_group(all, "box", path);
    const auto dim = read_attr_ints(box, "dimension", "particles/all/box", path);
    if (dim.size() != 1 || dim[0] != 3) throw IoError(path + ": box dimension is not 3");
    H b = open_attr(box, "boundary", "particles/all/box", path);
    const auto bnd = read_strings(b, true, "box boundary", path);
    if (bnd.size() != 3) throw IoError(path + ": box boundary does not have 3 entries");
    info.periodic = bnd[0] == "periodic";
    if (has_link(box, "edges")) {
      H5O_info_t oi;
      if (H5Oget_info_by_name(box, "edges", &oi, H5P_DEFAULT) < 0) fail(path, "cannot inspect box/edges");
      info.sheared_box = oi.type == H5O_TYPE_GROUP;
      if (info.sheared_box && check_element(box, "edges", path) != info.frames)
        throw IoError(path + ": box/edges and position hold different numbers of frames");
    } else if (info.periodic) {
      throw IoError(path + ": periodic box without particles/all/box/edges");
    }
  }
  if (info.frames > 0) {
    const auto steps = read_vector<std::int64_t>(all, "position/step", H5T_NATIVE_INT64, path);
    const auto times = read_vector<double>(all, "position/time", H5T_NATIVE_DOUBLE, path);
    info.first_step = steps.front();
    info.last_step = steps.back();
    info.last_time = times.back();
  }
  {
    H obs = open_group(f, "observables", path);
    collect_elements(obs, "", info.observables, path);
    for (const auto& o : info.observables) check_element(obs, o, path);
  }
  H p = open_group(f, "parameters/stokesian", path);
  info.scene_toml = read_string_dataset(p, "scene", path);
  info.model = read_string_dataset(p, "model", path);
  // Files of 0.1.0 have no model_key: read the key from their model description.
  info.model_key = has_link(p, "model_key") ? read_string_dataset(p, "model_key", path)
                                            : ModelKey::from_legacy_description(info.model).text();
  info.version = read_string_dataset(p, "version", path);
  return info;
}

// Names and shapes of per-particle fields, in name order.
std::vector<std::pair<std::string, std::vector<int>>> field_set(const std::vector<FieldSpec>& fields) {
  std::vector<std::pair<std::string, std::vector<int>>> out;
  for (const auto& f : fields) out.emplace_back(f.name, f.shape);
  std::sort(out.begin(), out.end());
  return out;
}

void require_matches(const TrajectoryInfo& info, const RunHeader& h, const std::string& path) {
  auto refuse = [&](const std::string& why) {
    throw IoError(path + ": cannot continue this trajectory: " + why);
  };
  if (info.particles != h.particles)
    refuse("it holds " + std::to_string(info.particles) + " particles, the run has " + std::to_string(h.particles));
  if (info.periodic != h.domain.periodic()) refuse("box boundary differs");
  // Edges per frame hold any box; a fixed edges dataset (unsheared boxes in files of 0.1.0) cannot
  // follow a sheared one.
  if (!info.sheared_box && h.domain.periodic() && h.sheared_box) refuse("sheared box differs");
  if (field_set(info.particle_fields) != field_set(h.particle_fields)) refuse("recorded per-particle quantities differ");
  if (const auto diff = scene_differences(info.scene_toml, h.scene_toml); !diff.empty()) {
    std::string keys;
    for (std::size_t i = 0; i < diff.size(); ++i) keys += (i ? "; " : "") + diff[i];
    refuse("the scene differs from the one stored in parameters/stokesian/scene (file -> this scene): " + keys);
  }
  const ModelKey file_key = ModelKey::from_stored(info.model_key), run_key = ModelKey::from_stored(h.model_key);
  if (file_key != run_key || (file_key.empty() && info.model != h.model))
    refuse("the model differs (file: \"" + (file_key.empty() ? info.model : file_key.text()) + "\", run: \"" +
           (run_key.empty() ? h.model : run_key.text()) + "\")");
}

}  // namespace

// ------------------------------------------------------------------------------------------------

TrajectoryInfo inspect_trajectory(const std::string& path) {
  H f = open_file(path, H5F_ACC_RDONLY);
  return inspect_open(f, path);
}

Trajectory Trajectory::create(const std::string& path, const RunHeader& header) {
  Trajectory t(path, header);
  for (const auto& stale : {t.shadow_path(), t.shadow_path() + ".tmp", path + ".old", path + ".tmp"})
    detail::remove_if_exists(stale);
  write_layout(path + ".tmp", header);
  detail::fsync_file(path + ".tmp");
  detail::durable_rename(path + ".tmp", path);
  detail::durable_copy(path, t.shadow_path());
  return t;
}

Trajectory Trajectory::resume(const std::string& path, const RunHeader& header, std::int64_t last_step,
                              std::int64_t expected_frames) {
  Trajectory t(path, header);
  const std::string S = t.shadow_path(), tmp = path + ".tmp";
  // Leftovers of an interrupted commit: P.old is never newer than P, temp files are partial.
  for (const auto& stale : {path + ".old", tmp, S + ".tmp"}) detail::remove_if_exists(stale);

  // Source: P if it passes the consistency check; otherwise the shadow (it may lack the last
  // segment, which the frame count below detects).
  // Files written before image counts existed (0.1.0) continue without the image element: their
  // checkpoints hold no counts.
  auto adapted = [&header](const TrajectoryInfo& info) {
    RunHeader h = header;
    if (!info.records("image"))
      h.particle_fields.erase(std::remove_if(h.particle_fields.begin(), h.particle_fields.end(),
                                             [](const FieldSpec& f) { return f.name == "image"; }),
                              h.particle_fields.end());
    return h;
  };
  std::string source, p_problem;
  try {
    const TrajectoryInfo info = inspect_trajectory(path);
    t.header_ = adapted(info);
    require_matches(info, t.header_, path);
    source = path;
  } catch (const IoError& e) {
    p_problem = e.what();
    if (p_problem.find("cannot continue") != std::string::npos) throw;
  }
  if (source.empty()) {
    try {
      const TrajectoryInfo info = inspect_trajectory(S);
      t.header_ = adapted(info);
      require_matches(info, t.header_, S);
      source = S;
    } catch (const IoError& e) {
      throw IoError(path + ": cannot resume: trajectory unusable (" + p_problem + ") and shadow unusable (" + e.what() + ")");
    }
  }

  detail::durable_copy(source, tmp);  // writes tmp + ".tmp", renames to tmp
  {
    H f = open_file(tmp, H5F_ACC_RDWR);
    truncate_elements(f, tmp, last_step);
    const std::int64_t frames = frames_in(f, tmp);
    if (frames != expected_frames) {
      f.reset();
      detail::remove_if_exists(tmp);
      throw IoError(path + ": checkpoint and trajectory are inconsistent: the checkpoint (step " +
                    std::to_string(last_step) + ") expects " + std::to_string(expected_frames) +
                    " frames with step <= " + std::to_string(last_step) + ", " + source + " holds " +
                    std::to_string(frames));
    }
    if (frames > 0) {
      H all = open_group(f, "particles/all", tmp);
      t.last_step_ = read_vector<std::int64_t>(all, "position/step", H5T_NATIVE_INT64, tmp).back();
      t.any_step_ = true;
    }
    f.close(tmp);
  }
  detail::fsync_file(tmp);
  detail::durable_rename(tmp, path);
  detail::durable_copy(path, S);
  t.committed_ = expected_frames;
  return t;
}

void Trajectory::check_frame(const Frame& f) const {
  for (const FieldSpec& spec : header_.particle_fields) {
    auto it = f.particles.find(spec.name);
    const std::size_t per = static_cast<std::size_t>(spec.item_size());
    const std::size_t entries = it == f.particles.end() ? 0 : it->second.values.size() / per;
    if (it == f.particles.end() || it->second.values.size() != header_.particles * per || it->second.shape != spec.shape)
      throw IoError(path_ + ": frame at step " + std::to_string(f.step) + " has " + std::to_string(entries) + " " +
                    spec.name + " entries for " + std::to_string(header_.particles) + " particles");
  }
  if (any_step_ && f.step <= last_step_)
    throw IoError(path_ + ": frame step " + std::to_string(f.step) + " does not follow step " + std::to_string(last_step_));
  for (const auto& [name, field] : f.observables) {
    if (field.values.empty() || field.values.size() != static_cast<std::size_t>(item_size(field.shape)))
      throw IoError(path_ + ": observable " + name + " has " + std::to_string(field.values.size()) +
                    " values for its shape");
  }
}

void Trajectory::append(Frame frame) {
  check_frame(frame);
  last_step_ = frame.step;
  any_step_ = true;
  std::size_t bytes = 0;
  for (const FieldSpec& spec : header_.particle_fields) bytes += frame.particles.at(spec.name).values.size() * 8;
  pending_bytes_ += bytes;
  pending_.push_back(std::move(frame));
  if (pending_bytes_ > max_pending_bytes) commit();
}

void Trajectory::commit() {
  if (pending_.empty()) return;
  const std::string S = shadow_path(), old = path_ + ".old";
  const std::int64_t shadow_frames = committed_ - static_cast<std::int64_t>(previous_.size());

  // 1. Bring S up to date. If S is damaged, locked by a reader or not where we left it, replace
  //    it by a fresh copy of P (which already holds the previous segment).
  std::optional<H> f;
  bool rebuilt = shadow_suspect_;
  if (!rebuilt) {
    try {
      f.emplace(open_file(S, H5F_ACC_RDWR));
      if (frames_in(*f, S) != shadow_frames) rebuilt = true;
    } catch (const IoError&) {
      rebuilt = true;
    }
  }
  if (rebuilt) {
    f.reset();
    detail::durable_copy(path_, S);
    f.emplace(open_file(S, H5F_ACC_RDWR));
  }
  std::vector<const Frame*> todo;
  if (!rebuilt)
    for (const auto& fr : previous_) todo.push_back(&fr);
  for (const auto& fr : pending_) todo.push_back(&fr);
  shadow_suspect_ = true;
  append_frames(*f, S, header_, todo);
  f->close(S);
  detail::fsync_file(S);

  // 2. Swap: P.old keeps the current P reachable while S takes its name.
  detail::remove_if_exists(old);
  if (::link(path_.c_str(), old.c_str()) != 0)
    throw IoError("cannot link " + path_ + " to " + old + " (" + std::strerror(errno) + ")");
  if (::rename(S.c_str(), path_.c_str()) != 0)
    throw IoError("cannot rename " + S + " to " + path_ + " (" + std::strerror(errno) + ")");
  if (::rename(old.c_str(), S.c_str()) != 0)
    throw IoError("cannot rename " + old + " to " + S + " (" + std::strerror(errno) + ")");
  detail::fsync_parent_dir(path_);
  shadow_suspect_ = false;

  committed_ += static_cast<std::int64_t>(pending_.size());
  previous_ = std::move(pending_);
  pending_.clear();
  pending_bytes_ = 0;
}

void Trajectory::finish() {
  commit();
  detail::remove_if_exists(shadow_path());
  detail::fsync_parent_dir(path_);
  shadow_suspect_ = true;  // a later commit rebuilds S from P
}

void Trajectory::write_frames(const std::string& path, const RunHeader& header, const std::vector<Frame>& frames) {
  Trajectory t(path, header);
  for (const Frame& f : frames) {
    t.check_frame(f);
    t.last_step_ = f.step;
    t.any_step_ = true;
  }
  const std::string tmp = path + ".tmp";
  write_layout(tmp, header);
  {
    H f = open_file(tmp, H5F_ACC_RDWR);
    std::vector<const Frame*> todo;
    for (const Frame& fr : frames) todo.push_back(&fr);
    append_frames(f, tmp, header, todo);
    f.close(tmp);
  }
  detail::fsync_file(tmp);
  detail::durable_rename(tmp, path);
  detail::remove_if_exists(t.shadow_path());  // a previous run's working copy at this path
}

Snapshot read_frame(const std::string& path, std::int64_t index, bool present_only) {
  H f = open_file(path, H5F_ACC_RDONLY);
  Snapshot s;
  std::int64_t frame = -1;  // resolved from the position dataset
  auto row = [&](const std::string& name, std::size_t comps, std::vector<double>& out) -> hsize_t {
    H d = open_dataset(f, name, path);
    const auto dims = dims_of(d, path);
    if (dims.size() != (comps > 1 ? 3u : 2u) || (comps > 1 && dims[2] != comps))
      throw IoError(path + ": dataset " + name + " has an unexpected shape");
    if (dims[0] == 0) throw IoError(path + ": dataset " + name + " holds no frames");
    if (frame < 0) {
      frame = index < 0 ? std::int64_t(dims[0]) + index : index;
      if (frame < 0 || frame >= std::int64_t(dims[0]))
        throw IoError(path + ": frame " + std::to_string(index) + " does not exist (the file holds " +
                      std::to_string(dims[0]) + " frames)");
    }
    if (std::int64_t(dims[0]) <= frame) throw IoError(path + ": dataset " + name + " holds fewer frames than position");
    H fspace = checked(H5Dget_space(d), H5Sclose, path, "dataspace");
    std::vector<hsize_t> start(dims.size(), 0), count = dims;
    start[0] = hsize_t(frame);
    count[0] = 1;
    checked(H5Sselect_hyperslab(fspace, H5S_SELECT_SET, start.data(), nullptr, count.data(), nullptr), path, "selection");
    H mspace = checked(H5Screate_simple(static_cast<int>(count.size()), count.data(), nullptr), H5Sclose, path, "dataspace");
    out.assign(dims[1] * comps, 0.0);
    checked(H5Dread(d, H5T_NATIVE_DOUBLE, mspace, fspace, H5P_DEFAULT, out.data()), path, "cannot read " + name);
    return dims[1];
  };
  std::vector<double> pos, rad;
  const hsize_t n = row("/particles/all/position/value", 3, pos);
  const hsize_t nr = row("/particles/all/radius/value", 1, rad);
  if (n != nr) throw IoError(path + ": position and radius hold different particle numbers");
  s.position.resize(n);
  for (hsize_t i = 0; i < n; ++i) s.position[i] = Vec3(pos[3 * i], pos[3 * i + 1], pos[3 * i + 2]);
  s.radius = std::move(rad);
  if (has_link(f, "/particles/all/velocity")) {
    std::vector<double> v;
    if (row("/particles/all/velocity/value", 3, v) != n)
      throw IoError(path + ": velocity and position hold different particle numbers");
    s.velocity.resize(n);
    for (hsize_t i = 0; i < n; ++i) s.velocity[i] = Vec3(v[3 * i], v[3 * i + 1], v[3 * i + 2]);
  }
  // Open channels (engine/inflow.hpp): the particles present are the slots with id >= 0.
  if (has_link(f, "/particles/all/id")) {
    std::vector<double> id;
    if (row("/particles/all/id/value", 1, id) != n) throw IoError(path + ": id and position hold different particle numbers");
    s.id.assign(id.begin(), id.end());
  }
  if (!s.id.empty() && present_only) {
    const std::vector<std::int64_t> id = std::move(s.id);
    s.id.clear();
    std::size_t k = 0;
    for (hsize_t i = 0; i < n; ++i)
      if (id[i] >= 0) {
        s.position[k] = s.position[i];
        if (!s.velocity.empty()) s.velocity[k] = s.velocity[i];
        s.radius[k++] = s.radius[i];
      }
    s.position.resize(k);
    s.radius.resize(k);
    if (!s.velocity.empty()) s.velocity.resize(k);
  }
  const auto steps = read_vector<std::int64_t>(f, "/particles/all/position/step", H5T_NATIVE_INT64, path);
  const auto times = read_vector<double>(f, "/particles/all/position/time", H5T_NATIVE_DOUBLE, path);
  if (steps.empty() || times.empty()) throw IoError(path + ": /particles/all/position has no step/time entries");
  if (std::int64_t(steps.size()) <= frame || std::int64_t(times.size()) <= frame)
    throw IoError(path + ": /particles/all/position has fewer step/time entries than frames");
  s.step = steps[std::size_t(frame)];
  s.time = times[std::size_t(frame)];
  {
    H box = open_group(f, "/particles/all/box", path);
    H b = open_attr(box, "boundary", "particles/all/box", path);
    const auto bnd = read_strings(b, true, "box boundary", path);
    s.periodic = !bnd.empty() && bnd[0] == "periodic";
    if (s.periodic) {
      H5O_info_t oi;
      if (H5Oget_info_by_name(box, "edges", &oi, H5P_DEFAULT) < 0) fail(path, "cannot inspect box/edges");
      if (oi.type == H5O_TYPE_GROUP) {  // edges per frame: rows a = (Lx,0,0), b = (strain Ly, Ly, 0), c = (0,0,Lz)
        std::vector<double> e;
        row("/particles/all/box/edges/value", 3, e);
        if (e.size() != 9) throw IoError(path + ": box/edges/value is not 3 x 3 per frame");
        s.box = Vec3(e[0], e[4], e[8]);
        s.shear_strain = e[3] / e[4];
      } else {  // one fixed edges vector (unsheared boxes in files of 0.1.0)
        const auto e = read_vector<double>(f, "/particles/all/box/edges", H5T_NATIVE_DOUBLE, path);
        if (e.size() != 3) throw IoError(path + ": box/edges does not hold 3 lengths");
        s.box = Vec3(e[0], e[1], e[2]);
      }
    }
  }
  return s;
}

Snapshot read_last_frame(const std::string& path) { return read_frame(path, -1, true); }

namespace {
// Writes each column as a 1D dataset of group g (numbers as float64, text as fixed-length strings);
// returns the stored names ('/' replaced by '|').
std::vector<std::string> write_columns(hid_t g, const std::vector<TableColumn>& columns, const std::string& tmp) {
  std::vector<std::string> names;
  for (const auto& c : columns) {
    std::string name = c.name;
    std::replace(name.begin(), name.end(), '/', '|');
    names.push_back(name);
    if (c.numeric) {
      const hsize_t n = c.num.size();
      H space = checked(H5Screate_simple(1, &n, nullptr), H5Sclose, tmp, "dataspace");
      H d = checked(H5Dcreate2(g, name.c_str(), H5T_IEEE_F64LE, space, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), H5Dclose,
                    tmp, "cannot create dataset " + name);
      if (n) checked(H5Dwrite(d, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, c.num.data()), tmp, "cannot write " + name);
    } else {
      std::size_t len = 0;
      for (const auto& t : c.text) len = std::max(len, t.size());
      H type = string_type(len, tmp);
      const std::size_t width = len + 1;
      std::vector<char> buf(width * c.text.size(), '\0');
      for (std::size_t i = 0; i < c.text.size(); ++i) std::memcpy(buf.data() + i * width, c.text[i].data(), c.text[i].size());
      const hsize_t n = c.text.size();
      H space = checked(H5Screate_simple(1, &n, nullptr), H5Sclose, tmp, "dataspace");
      H d = checked(H5Dcreate2(g, name.c_str(), type, space, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), H5Dclose, tmp,
                    "cannot create dataset " + name);
      if (n) checked(H5Dwrite(d, type, H5S_ALL, H5S_ALL, H5P_DEFAULT, buf.data()), tmp, "cannot write " + name);
    }
  }
  return names;
}
}  // namespace

void write_table_h5(const std::string& path, const std::vector<TableColumn>& columns,
                    const std::vector<std::pair<std::string, std::string>>& attributes) {
  quiet_hdf5();
  const std::string tmp = path + ".tmp." + std::to_string(::getpid());
  {
    H f = checked(H5Fcreate(tmp.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT), H5Fclose, tmp, "cannot create file");
    H g = make_group(f, "table", tmp);
    const std::vector<std::string> names = write_columns(g, columns, tmp);
    {
      std::size_t len = 0;
      for (const auto& t : names) len = std::max(len, t.size());
      H type = string_type(len, tmp);
      const std::size_t width = len + 1;
      std::vector<char> buf(width * names.size(), '\0');
      for (std::size_t i = 0; i < names.size(); ++i) std::memcpy(buf.data() + i * width, names[i].data(), names[i].size());
      const hsize_t n = names.size();
      H space = checked(H5Screate_simple(1, &n, nullptr), H5Sclose, tmp, "dataspace");
      H d = checked(H5Dcreate2(f, "table_columns", type, space, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), H5Dclose, tmp,
                    "cannot create dataset table_columns");
      if (n) checked(H5Dwrite(d, type, H5S_ALL, H5S_ALL, H5P_DEFAULT, buf.data()), tmp, "cannot write table_columns");
    }
    for (const auto& [k, v] : attributes) write_attr_strings(f, k, {v}, true, tmp);
    f.close(tmp);
  }
  detail::durable_rename(tmp, path);
}

void write_tables_h5(const std::string& path, const std::vector<TableGroup>& groups, const std::vector<Matrix2D>& matrices,
                     const std::vector<std::pair<std::string, std::string>>& attributes) {
  quiet_hdf5();
  const std::string tmp = path + ".tmp." + std::to_string(::getpid());
  {
    H f = checked(H5Fcreate(tmp.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT), H5Fclose, tmp, "cannot create file");
    for (const TableGroup& t : groups) {
      H g = make_group(f, t.name, tmp);
      write_columns(g, t.columns, tmp);
    }
    for (const Matrix2D& m : matrices) {
      if (m.data.size() != m.rows * m.cols) throw IoError(tmp + ": matrix " + m.name + " has the wrong number of values");
      const hsize_t dims[2] = {m.rows, m.cols};
      H space = checked(H5Screate_simple(2, dims, nullptr), H5Sclose, tmp, "dataspace");
      H d = checked(H5Dcreate2(f, m.name.c_str(), H5T_IEEE_F64LE, space, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), H5Dclose,
                    tmp, "cannot create dataset " + m.name);
      if (!m.data.empty())
        checked(H5Dwrite(d, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, m.data.data()), tmp, "cannot write " + m.name);
    }
    for (const auto& [k, v] : attributes) write_attr_strings(f, k, {v}, true, tmp);
    f.close(tmp);
  }
  detail::durable_rename(tmp, path);
}

std::vector<ObservableSeries> read_observables(const std::string& path) {
  const TrajectoryInfo info = inspect_trajectory(path);  // full consistency check first
  H f = open_file(path, H5F_ACC_RDONLY);
  std::vector<ObservableSeries> out;
  for (const auto& name : info.observables) {
    ObservableSeries o;
    o.name = name;
    const std::string g = "/observables/" + name;
    o.time = read_vector<double>(f, g + "/time", H5T_NATIVE_DOUBLE, path);
    H d = open_dataset(f, g + "/value", path);
    const auto dims = dims_of(d, path);
    if (dims.empty() || dims[0] != o.time.size()) throw IoError(path + ": " + g + "/value does not match its time");
    for (std::size_t k = 1; k < dims.size(); ++k) o.components *= dims[k];
    o.value.assign(o.time.size() * o.components, 0.0);
    if (!o.value.empty())
      checked(H5Dread(d, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, o.value.data()), path, "cannot read " + g + "/value");
    if (H5Aexists(d, "unit") > 0) {
      H a = open_attr(d, "unit", g + "/value", path);
      const auto u = read_strings(a, true, "unit", path);
      if (!u.empty()) o.unit = u[0];
    }
    out.push_back(std::move(o));
  }
  return out;
}

}  // namespace stokesian::io
