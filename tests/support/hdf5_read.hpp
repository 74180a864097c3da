#pragma once
// Reading a whole dataset back with the HDF5 C API, independently of io/.
#include <doctest/doctest.h>
#include <hdf5.h>

#include <string>
#include <vector>

namespace stokesian::test {

inline std::vector<double> read_doubles(const std::string& file, const std::string& dset) {
  const hid_t f = H5Fopen(file.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  REQUIRE(f >= 0);
  const hid_t d = H5Dopen2(f, dset.c_str(), H5P_DEFAULT);
  REQUIRE(d >= 0);
  const hid_t sp = H5Dget_space(d);
  std::vector<double> v(std::size_t(H5Sget_simple_extent_npoints(sp)));
  H5Dread(d, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, v.data());
  H5Sclose(sp);
  H5Dclose(d);
  H5Fclose(f);
  return v;
}

}  // namespace stokesian::test
