// A failed write of an output (a full disk), in process: the fault hook (io_fault.hpp) fails the
// first, a middle and the last write call of a file, its flush and its rename; each must end in
// one WriteError naming the file and the cause in words, with the earlier file byte-for-byte as it
// was, no temporary file left and no HDF5 object left open (the crash of issue 33 was a file left
// half-closed inside libhdf5).
#include "harness/io/atomic_file.hpp"
#include "harness/io/io_fault.hpp"
#include "harness/io/matrix_market.hpp"
#include "harness/io/recorder.hpp"
#include "harness/io/system_io.hpp"

#include "test_support.hpp"

#include <hdf5.h>

#include <cerrno>
#include <fstream>
#include <iterator>
#include <map>

namespace fs = std::filesystem;
using namespace xb;
using xb::test::TempDir;

namespace {

std::string bytes_of(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), {}};
}

// The write calls of a file of `size` bytes: its chunks, then its fsync (atomic_file.hpp).
long calls_for(std::uintmax_t size) { return static_cast<long>((size + write_chunk - 1) / write_chunk) + 1; }

// Faults off again when a test ends, however it ends.
struct Faults {
  Faults(const std::string& write, const std::string& rename) { io_fault::set(write, rename); }
  ~Faults() { io_fault::set("", ""); }
};

RunRecord run_named(const std::string& name, size_t n) {
  RunRecord r;
  r.name = name;
  r.attrs["level"] = std::string("simulation");
  r.attrs["status"] = std::string("ok");
  std::vector<double> v(n);
  for (size_t i = 0; i < n; ++i) v[i] = 1.0 / static_cast<double>(i + 1);
  r.datasets["dual_residual"] = v;
  return r;
}

// `write` with the fault `fault` (N:ERRNO for writes, or "rename" for the first rename) must
// throw one WriteError naming `target` and `words`, leave `target` as `before` and no .tmp.
template <class Write>
void expect_failed_write(Write write, const std::string& target, const std::string& before, const std::string& fault,
                         const std::string& words) {
  SCOPED_TRACE("fault " + fault);
  {
    Faults f(fault == "rename" ? "" : fault, fault == "rename" ? "1:EROFS" : "");
    try {
      write();
      ADD_FAILURE() << "no error";
    } catch (const WriteError& e) {
      const std::string msg = e.what();
      EXPECT_NE(msg.find(target), std::string::npos) << msg;
      EXPECT_NE(msg.find(words), std::string::npos) << msg;
      EXPECT_NE(msg.find("is left as it was"), std::string::npos) << msg;
      EXPECT_EQ(msg.find('\n'), std::string::npos) << msg;
      EXPECT_EQ(e.path, target);
    }
  }
  EXPECT_TRUE(bytes_of(target) == before) << target << " changed";
  const fs::path dir = fs::path(target).parent_path();
  for (const auto& e : fs::recursive_directory_iterator(dir)) EXPECT_NE(e.path().extension(), ".tmp") << e.path();
  EXPECT_EQ(H5Fget_obj_count(H5F_OBJ_ALL, H5F_OBJ_ALL), 0) << "HDF5 objects left open";
}

}  // namespace

TEST(AtomicFile, ErrnoInWords) {
  EXPECT_EQ(errno_text(ENOSPC), "no space left on device");
  EXPECT_EQ(errno_text(EFBIG), "file too large");
  EXPECT_EQ(errno_text(EROFS), "read-only file system");
}

TEST(AtomicFile, FaultSpecIsCheckedAndNamed) {
  for (const char* bad : {"3", "0:ENOSPC", "x:ENOSPC", "2:ENOPE", "2:"}) {
    try {
      io_fault::set(bad, "");
      ADD_FAILURE() << bad << " accepted";
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find(std::string("XB_FAULT_WRITE=") + bad), std::string::npos) << e.what();
    }
  }
  io_fault::set("", "");
}

TEST(AtomicFile, EveryWriteCallOfAFileCanFailAndNothingChanges) {
  TempDir d;
  const std::string target = d / "blob.bin";
  std::string data(3 * write_chunk + 100, 'x');
  for (size_t i = 0; i < data.size(); ++i) data[i] = static_cast<char>(i * 7);
  write_file_atomically(target, "earlier", 7);
  const long calls = calls_for(data.size());
  ASSERT_EQ(calls, 5);  // four chunks and the fsync
  auto write = [&] { write_file_atomically(target, data.data(), data.size()); };
  for (long k = 1; k <= calls; ++k) expect_failed_write(write, target, "earlier", std::to_string(k) + ":ENOSPC", "no space left on device");
  expect_failed_write(write, target, "earlier", "2:EFBIG", "file too large");
  expect_failed_write(write, target, "earlier", "rename", "read-only file system");
  {
    Faults f(std::to_string(calls + 1) + ":ENOSPC", "");  // one call past the file: it is written
    write();
  }
  EXPECT_TRUE(bytes_of(target) == data);
}

TEST(AtomicFile, TextWritersStopAtTheFirstFailedWrite) {
  TempDir d;
  const std::string target = d / "b.mtx";
  Vector b = Vector::LinSpaced(5000, 0.0, 1.0);  // ~100 KB of %.17g text: several chunks
  write_matrix_market(target, Vector::Ones(3));
  const std::string before = bytes_of(target);
  {
    TmpFile probe(d / "probe.mtx");
    write_matrix_market(probe, b);
    probe.commit();
  }
  const long calls = calls_for(fs::file_size(d / "probe.mtx"));
  ASSERT_GE(calls, 4);
  auto write = [&] { write_matrix_market(target, b); };
  for (long k : {1L, calls / 2, calls - 1, calls}) expect_failed_write(write, target, before, std::to_string(k) + ":ENOSPC", "no space left on device");
  expect_failed_write(write, target, before, "rename", "read-only file system");
}

namespace {
// A results file as the user sees it: the index and every file in its runs folder and store (by name).
std::map<std::string, std::string> results_bytes(const std::string& path) {
  std::map<std::string, std::string> files{{"index", bytes_of(path)}};
  for (const auto& e : fs::recursive_directory_iterator(runs_folder(path)))
    if (e.is_regular_file() && e.path().filename() != "lock") files[e.path().filename().string()] = bytes_of(e.path().string());
  return files;
}
}  // namespace

// An append writes the run's file (chunks, flush, its link into the store: rename 1) and then the
// new index (chunks, flush, rename 2): a fault at any of them leaves the index and the runs folder
// as they were.
TEST(AtomicFile, ResultsFileFailsAtFirstMiddleLastWriteFlushAndRename) {
  TempDir d;
  const std::string out = d / "r.h5";
  append_runs(out, {run_named("earlier", 10)}, true);
  const auto before = results_bytes(out);
  // What the append writes: the probe is the same append to another file of one run.
  const std::string probe = d / "probe.h5";
  append_runs(probe, {run_named("earlier", 10)}, true);
  const RunRecord added = run_named("added", 8000);  // 64 KB of doubles: several chunks
  append_runs(probe, {added});
  long run_calls = 0;
  for (const auto& e : fs::recursive_directory_iterator(runs_folder(probe)))
    if (e.path().filename().string().starts_with("0002_added.")) run_calls = calls_for(fs::file_size(e.path()));
  const long index_calls = calls_for(fs::file_size(probe));
  ASSERT_GE(run_calls, 5);
  auto append = [&] { append_runs(out, {added}); };
  for (long k : {1L, run_calls / 2, run_calls - 1, run_calls, run_calls + 1, run_calls + index_calls - 1, run_calls + index_calls}) {
    expect_failed_write(append, out, before.at("index"), std::to_string(k) + ":ENOSPC", "no space left on device");
    EXPECT_TRUE(results_bytes(out) == before) << "fault at write " << k << ": the runs folder changed";
  }
  expect_failed_write(append, out, before.at("index"), "rename", "read-only file system");  // the run file's
  {
    Faults f("", "2:EIO");  // the index's
    EXPECT_THROW(append(), WriteError);
  }
  EXPECT_TRUE(results_bytes(out) == before) << "a failed rename of the index left a run file";
  // A fresh file fails the same way, and the earlier one stays.
  auto fresh = [&] { append_runs(out, {added}, true); };
  expect_failed_write(fresh, out, before.at("index"), "1:EDQUOT", "quota exceeded");
  EXPECT_TRUE(results_bytes(out) == before);
  append_runs(out, {added});  // and with no fault the append works after all of them
  EXPECT_EQ(count_runs(out), 2);
  EXPECT_EQ(fs::file_size(out), fs::file_size(probe));
}

TEST(AtomicFile, CaptureReplacesNoFileWhenAWriteFails) {
  TempDir d;
  CapturedSystem sys;
  const int n = 2000;
  std::vector<Eigen::Triplet<double, int>> t;
  for (int i = 0; i < n; ++i) {
    t.emplace_back(i, i, 4.0);
    if (i > 0) t.emplace_back(i, i - 1, -1.0), t.emplace_back(i - 1, i, -1.0);
  }
  sys.A.resize(n, n);
  sys.A.setFromTriplets(t.begin(), t.end());
  sys.A.makeCompressed();
  sys.b = Vector::LinSpaced(n, 1.0, 2.0);
  const std::string prefix = d / "sys";
  CapturedSystem earlier = sys;
  earlier.b *= 3.0;
  write_captured_system(prefix, earlier);
  const std::vector<std::string> files = {prefix + ".h5", prefix + "_A.mtx", prefix + "_b.mtx"};
  std::vector<std::string> before;
  for (const auto& f : files) before.push_back(bytes_of(f));
  long calls = 0;
  for (const auto& f : write_captured_system(d / "probe", sys)) calls += calls_for(fs::file_size(f));
  for (const std::string& fault : std::vector<std::string>{"1:ENOSPC", std::to_string(calls / 2) + ":ENOSPC", std::to_string(calls) + ":ENOSPC"}) {
    SCOPED_TRACE(fault);
    Faults f(fault, "");
    try {
      write_captured_system(prefix, sys);
      ADD_FAILURE() << "no error";
    } catch (const WriteError& e) {
      EXPECT_NE(std::string(e.what()).find("no file of " + prefix + " was replaced"), std::string::npos) << e.what();
    }
    for (size_t i = 0; i < files.size(); ++i) EXPECT_TRUE(bytes_of(files[i]) == before[i]) << files[i] << " changed";
    for (const auto& p : fs::directory_iterator(d.path)) EXPECT_NE(p.path().extension(), ".tmp") << p.path();
  }
  // A rename that fails after others: the message says which were replaced.
  Faults f("", "2:EIO");
  try {
    write_captured_system(prefix, sys);
    ADD_FAILURE() << "no error";
  } catch (const WriteError& e) {
    EXPECT_NE(std::string(e.what()).find("already replaced: " + prefix + "_A.mtx"), std::string::npos) << e.what();
  }
  EXPECT_TRUE(bytes_of(prefix + ".h5") == before[0]) << prefix << ".h5 changed";
  for (const auto& p : fs::directory_iterator(d.path)) EXPECT_NE(p.path().extension(), ".tmp") << p.path();
}
