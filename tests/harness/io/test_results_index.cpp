// One results file, many writers (harness/io/recorder.hpp, results_index.hpp, file_lock.hpp):
// concurrent appends keep every run under unique names, an append writes what it adds and not what
// the file holds, a replaced file stays one writer's, a packed file is one file, an inline file is
// moved into a store on its first append, and what a killed writer left is cleaned up.
#include "harness/io/atomic_file.hpp"
#include "harness/io/file_lock.hpp"
#include "harness/io/h5handle.hpp"
#include "harness/io/io_fault.hpp"
#include "harness/io/recorder.hpp"

#include "test_support.hpp"

#include <hdf5.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <fstream>
#include <set>
#include <thread>

namespace fs = std::filesystem;
using namespace xb;
using xb::test::TempDir;

namespace {

RunRecord run_of(const std::string& name, size_t n, double scale = 1.0) {
  RunRecord r;
  r.name = name;
  r.attrs["level"] = std::string("simulation");
  r.attrs["status"] = std::string("ok");
  std::vector<double> v(n);
  for (size_t i = 0; i < n; ++i) v[i] = scale / static_cast<double>(i + 1);
  r.datasets["dual_residual"] = v;
  return r;
}

std::vector<std::string> names_of(const std::vector<RunRecord>& runs) {
  std::vector<std::string> out;
  for (const auto& r : runs) out.push_back(r.name);
  return out;
}

std::vector<std::string> files_in(const std::string& dir) {
  std::vector<std::string> out;
  std::error_code ec;
  for (fs::recursive_directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec))
    if (it->is_regular_file()) out.push_back(it->path().filename().string());
  return out;
}

}  // namespace

TEST(ResultsFile, RunsAreNumberedAfterThoseInTheFileAndEachIsAFileOfItsOwn) {
  TempDir d;
  const std::string out = d / "r.h5";
  EXPECT_EQ(append_runs(out, {run_of("cloth_cg", 4), run_of("cloth_gs", 4)}), (std::vector<std::string>{"0001_cloth_cg", "0002_cloth_gs"}));
  EXPECT_EQ(append_runs(out, {run_of("cloth_cg", 4)}), std::vector<std::string>{"0003_cloth_cg"});
  const auto runs = read_runs(out, true);
  EXPECT_EQ(names_of(runs), (std::vector<std::string>{"0001_cloth_cg", "0002_cloth_gs", "0003_cloth_cg"}));
  int run_files = 0;
  for (const auto& f : files_in(runs_folder(out))) run_files += f.ends_with(".h5");
  EXPECT_EQ(run_files, 3);
  // Each run file is a results file holding that run.
  for (const auto& e : fs::directory_iterator(runs_folder(out))) {
    if (e.path().extension() != ".h5") continue;
    EXPECT_EQ(read_runs(e.path().string()).size(), 1u) << e.path();
  }
}

// What an append writes is the run and the index, not the runs already there: the same run
// appended to a file of one run and to one of 30 runs of 256 KB costs the same write calls (the
// index grows by a link per run, ~120 bytes). Rewriting the file, as once, took ~500 more.
TEST(ResultsFile, AnAppendWritesWhatItAddsNotWhatTheFileHolds) {
  TempDir d;
  const std::string small = d / "small.h5", large = d / "large.h5";
  append_runs(small, {run_of("x", 16)});
  for (int i = 0; i < 30; ++i) append_runs(large, {run_of("big", 32768, i)});
  const RunRecord added = run_of("added", 8000);  // 64 KB: several chunks
  long before = io_fault::write_calls();
  append_runs(small, {added});
  const long into_small = io_fault::write_calls() - before;
  before = io_fault::write_calls();
  append_runs(large, {added});
  const long into_large = io_fault::write_calls() - before;
  EXPECT_GE(into_small, 6);
  EXPECT_LE(into_large, into_small + 1) << "an append to a file of 30 runs wrote " << into_large << " calls, to one of 1 run "
                                        << into_small;
  EXPECT_EQ(count_runs(large), 31);
}

// Threads of one process exclude each other as processes do (open-file-description locks), and
// libhdf5 is entered by one thread at a time (h5handle.hpp): 6 writers × 5 runs, all kept.
TEST(ResultsFile, ConcurrentWritersKeepEveryRunUnderUniqueNames) {
  TempDir d;
  const std::string out = d / "shared.h5";
  std::vector<std::thread> writers;
  for (int w = 0; w < 6; ++w)
    writers.emplace_back([&out, w] {
      ResultsWriter writer(out, false);
      for (int i = 0; i < 5; ++i) writer.add({run_of("writer" + std::to_string(w), 100, i)});
    });
  for (auto& t : writers) t.join();
  const auto runs = read_runs(out, true);
  ASSERT_EQ(runs.size(), 30u);
  std::set<std::string> numbers;
  for (const auto& r : runs) numbers.insert(r.name.substr(0, 4));
  EXPECT_EQ(numbers.size(), 30u);
  EXPECT_EQ(*numbers.rbegin(), "0030");
  for (const auto& f : files_in(d.path)) EXPECT_FALSE(f.ends_with(".tmp")) << f;
}

// run --out replaces by design: the file stays one writer's, whole; the displaced writer is told.
TEST(ResultsFile, AReplacedFileStaysTheLastWritersAndTheOtherIsTold) {
  TempDir d;
  const std::string out = d / "r.h5";
  ResultsWriter a(out, true), b(out, true);
  a.add({run_of("a", 10)});
  b.add({run_of("b", 10)});
  try {
    a.add({run_of("a", 10)});
    ADD_FAILURE() << "the displaced writer added a run";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("was replaced by another writer (pid"), std::string::npos) << e.what();
  }
  b.add({run_of("b", 10)});
  EXPECT_EQ(names_of(read_runs(out)), (std::vector<std::string>{"0001_b", "0002_b"}));
  // a's run file went with the file it replaced.
  int run_files = 0;
  for (const auto& f : files_in(runs_folder(out))) run_files += f.ends_with(".h5");
  EXPECT_EQ(run_files, 2);
}

// A copy of the file with its folder (cp -r r.h5 r.h5.runs backup/) is a copy: replacing r.h5
// leaves it whole.
TEST(ResultsFile, ReplacingAFileKeepsACopyOfIt) {
  TempDir d;
  const std::string out = d / "r.h5";
  append_runs(out, {run_of("kept", 50), run_of("kept", 50)});
  fs::create_directories(d.path / "backup");
  fs::copy(out, d.path / "backup/r.h5");
  fs::copy(runs_folder(out), d.path / "backup/r.h5.runs", fs::copy_options::recursive);
  append_runs(out, {run_of("new", 5)}, true);
  EXPECT_EQ(names_of(read_runs(d / "backup/r.h5", true)), (std::vector<std::string>{"0001_kept", "0002_kept"}));
  EXPECT_EQ(names_of(read_runs(out)), std::vector<std::string>{"0001_new"});
}

// pack: one self-contained file (groups, no links) that reads the same anywhere.
TEST(ResultsFile, PackMakesOneFileThatReadsTheSameElsewhere) {
  TempDir d;
  const std::string out = d / "r.h5";
  append_runs(out, {run_of("a", 300), run_of("b", 7)});
  fs::create_directories(d.path / "elsewhere");
  const std::string one = d / "elsewhere/one.h5";
  EXPECT_TRUE(pack_runs(out, one).empty());
  EXPECT_FALSE(fs::exists(runs_folder(one)));
  const auto packed = read_runs(one, true), original = read_runs(out, true);
  ASSERT_EQ(packed.size(), 2u);
  for (size_t i = 0; i < 2; ++i) {
    EXPECT_EQ(packed[i].name, original[i].name);
    EXPECT_TRUE(packed[i].datasets == original[i].datasets);
    EXPECT_TRUE(packed[i].attrs == original[i].attrs);
  }
  const h5::Guard guard;
  h5::H f(H5Fopen(one.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT), H5Fclose);
  H5L_info_t info;
  ASSERT_GE(H5Lget_info(f, "/runs/0001_a", &info, H5P_DEFAULT), 0);
  EXPECT_EQ(info.type, H5L_TYPE_HARD);
}

// A file of inline groups (packed, or written before run files) takes appends: its runs move into
// a store once, and the next append no longer copies them.
TEST(ResultsFile, AnInlineFileIsMovedToRunFilesOnItsFirstAppend) {
  TempDir d;
  const std::string out = d / "r.h5", one = d / "one.h5";
  append_runs(out, {run_of("a", 20000), run_of("b", 20000)});
  pack_runs(out, one);
  const auto before = read_runs(one, true);
  append_runs(one, {run_of("c", 10)});
  const auto after = read_runs(one, true);
  ASSERT_EQ(names_of(after), (std::vector<std::string>{"0001_a", "0002_b", "0003_c"}));
  for (size_t i = 0; i < 2; ++i) EXPECT_TRUE(after[i].datasets == before[i].datasets);
  EXPECT_LT(fs::file_size(one), 20000u) << "the index still holds the runs' data";
  const long calls = io_fault::write_calls();
  append_runs(one, {run_of("d", 10)});
  EXPECT_LE(io_fault::write_calls() - calls, 6);
}

// A temporary file whose writer is gone is removed by the next writer of the file; a live
// writer's is left alone.
TEST(ResultsFile, TemporaryFilesOfWritersThatAreGoneAreRemoved) {
  TempDir d;
  const std::string target = d / "blob.bin";
  const pid_t child = fork();
  if (child == 0) _exit(0);
  waitpid(child, nullptr, 0);  // a pid that no longer runs
  const std::string tag = writer_tag(), host = tag.substr(tag.find('@'));
  const std::string dead = d / (".blob.bin.0badcafe." + std::to_string(child) + host + ".tmp");
  const std::string alive = d / (".blob.bin.0badbeef." + tag + ".tmp");
  for (const auto& f : {dead, alive}) std::ofstream(f) << "half";
  write_file_atomically(target, "x", 1);
  EXPECT_FALSE(fs::exists(dead));
  EXPECT_TRUE(fs::exists(alive));
  // Under a results file's lock every temporary file of it is stale: removed by the next append.
  const std::string out = d / "r.h5";
  append_runs(out, {run_of("a", 3)});
  const std::string stale = d / (".r.h5.0badf00d." + tag + ".tmp");
  std::ofstream(stale) << "half";
  std::ofstream(runs_folder(out) + "/.0002_a.00000000.h5.0badf00d." + tag + ".tmp") << "half";
  append_runs(out, {run_of("a", 3)});
  for (const auto& f : files_in(d.path)) EXPECT_TRUE(!f.ends_with(".tmp") || f == fs::path(alive).filename()) << f;
}

// A writer that waits for another says so, once, and then writes.
TEST(ResultsFile, AWriterWaitingForTheLockSaysSo) {
  TempDir d;
  const std::string out = d / "r.h5";
  append_runs(out, {run_of("a", 3)});
  testing::internal::CaptureStderr();
  std::thread writer;
  std::atomic<bool> done{false};
  {
    FileLock held(runs_folder(out) + "/lock", FileLock::Kind::exclusive, out);
    writer = std::thread([&out, &done] {
      append_runs(out, {run_of("b", 3)});
      done = true;
    });
    std::this_thread::sleep_for(std::chrono::milliseconds(1500));
    EXPECT_FALSE(done) << "the writer did not wait for the lock";
  }
  writer.join();
  const std::string err = testing::internal::GetCapturedStderr();
  EXPECT_NE(err.find("waiting for " + out + ": another writer holds it"), std::string::npos) << err;
  EXPECT_EQ(count_runs(out), 2);
}
