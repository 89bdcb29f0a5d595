// Captured-system files (harness/system_io): a corrupt CSR array is named as what it is, and J
// survives the round trip through its CSR form.
#include "harness/cli/commands.hpp"
#include "harness/io/system_io.hpp"
#include "core/error.hpp"
#include "test_support.hpp"

#include <gtest/gtest.h>
#include <hdf5.h>

using namespace xb;
using namespace xb::test;

namespace {
// Overwrites entry `index` of the int64 dataset `name` in an HDF5 file.
void poke(const std::string& file, const char* name, hsize_t index, long long value) {
  const hid_t f = H5Fopen(file.c_str(), H5F_ACC_RDWR, H5P_DEFAULT);
  ASSERT_GE(f, 0);
  const hid_t ds = H5Dopen2(f, name, H5P_DEFAULT);
  const hid_t space = H5Dget_space(ds);
  const hsize_t one = 1;
  H5Sselect_hyperslab(space, H5S_SELECT_SET, &index, nullptr, &one, nullptr);
  const hid_t mem = H5Screate_simple(1, &one, nullptr);
  EXPECT_GE(H5Dwrite(ds, H5T_NATIVE_LLONG, mem, space, H5P_DEFAULT, &value), 0);
  H5Sclose(mem);
  H5Sclose(space);
  H5Dclose(ds);
  H5Fclose(f);
}

// Replaces /b by a chunked dataset of n doubles, deflated; `values` written unless empty.
void replace_b(const std::string& file, hsize_t n, const Vector& values) {
  const hid_t f = H5Fopen(file.c_str(), H5F_ACC_RDWR, H5P_DEFAULT);
  ASSERT_GE(f, 0);
  EXPECT_GE(H5Ldelete(f, "/b", H5P_DEFAULT), 0);
  const hid_t space = H5Screate_simple(1, &n, nullptr);
  const hid_t dcpl = H5Pcreate(H5P_DATASET_CREATE);
  const hsize_t chunk = 16;
  H5Pset_chunk(dcpl, 1, &chunk);
  H5Pset_deflate(dcpl, 6);
  const hid_t ds = H5Dcreate2(f, "/b", H5T_NATIVE_DOUBLE, space, H5P_DEFAULT, dcpl, H5P_DEFAULT);
  if (values.size()) {
    EXPECT_GE(H5Dwrite(ds, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, values.data()), 0);
  }
  H5Dclose(ds);
  H5Pclose(dcpl);
  H5Sclose(space);
  H5Fclose(f);
}

void expect_error(const std::string& file, const std::string& fragment) {
  try {
    read_system_h5(file);
    ADD_FAILURE() << file << " was read";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find(fragment), std::string::npos) << e.what();
  }
}
}  // namespace

TEST(SystemIo, RowPointerPastTheArraysIsNamed) {
  TempDir dir;
  const std::string prefix = dir / "sys";
  ASSERT_EQ(cmd_capture({"--scene", "cloth_hang", "--set", "resolution=4", "--frame", "0", "--iteration", "0", "--out", prefix}), 0);
  const CapturedSystem good = read_system_h5(prefix + ".h5");
  ASSERT_TRUE(good.has_primal());
  // A row pointer in the middle of /A that overruns the arrays (the last one is still right).
  poke(prefix + ".h5", "/A/indptr", 3, 1LL << 40);
  expect_error(prefix + ".h5", "/A/indptr is not non-decreasing");
  // The same in /J.
  ASSERT_EQ(cmd_capture({"--scene", "cloth_hang", "--set", "resolution=4", "--frame", "0", "--iteration", "0", "--out", prefix}), 0);
  poke(prefix + ".h5", "/J/indptr", 2, 1LL << 40);
  expect_error(prefix + ".h5", "/J/indptr is not non-decreasing");
}

// Values are allocated only when the file stores them: a compressed /b reads back, a declared
// extent over chunks never written is refused before its gigabytes are allocated.
TEST(SystemIo, DeclaredValuesMustBeStored) {
  TempDir dir;
  const std::string prefix = dir / "sys";
  ASSERT_EQ(cmd_capture({"--scene", "cloth_hang", "--set", "resolution=3", "--frame", "0", "--iteration", "0", "--out", prefix}), 0);
  const CapturedSystem good = read_system_h5(prefix + ".h5");
  replace_b(prefix + ".h5", good.b.size(), good.b);
  EXPECT_EQ(read_system_h5(prefix + ".h5").b, good.b);
  replace_b(prefix + ".h5", hsize_t{1} << 28, Vector());
  expect_error(prefix + ".h5", "/b: declares 268435456 values (2147483648 bytes) but the file stores only 0 bytes");
}

TEST(SystemIo, JacobianRowWithMoreThanFourParticlesIsRefused) {
  SparseMatrix J(1, 15);
  for (int c = 0; c < 15; c += 3) J.insert(0, c) = 1.0;
  J.makeCompressed();
  ConstraintGraph g;
  Gradients grad;
  EXPECT_THROW(jacobian_from_csr(J, g, grad), Error);
}
