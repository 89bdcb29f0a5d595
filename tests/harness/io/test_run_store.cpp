// The results store (harness/io/run_store.hpp, results_index.hpp, store_upkeep.hpp): run file
// names, files that behave like files (renamed with their folder, copied, reached through a
// symbolic link, an index deleted by hand, a file of the earlier layout), a job kept once, locks
// that do not lock refused, readers that take no lock, and what `repair` finds.
#include "harness/io/atomic_file.hpp"
#include "harness/io/file_lock.hpp"
#include "harness/io/h5handle.hpp"
#include "harness/io/h5io.hpp"
#include "harness/io/io_fault.hpp"
#include "harness/io/recorder.hpp"

#include "test_support.hpp"

#include <hdf5.h>
#include <unistd.h>

#include <chrono>
#include <fstream>
#include <future>
#include <set>
#include <thread>

namespace fs = std::filesystem;
using namespace xb;
using xb::test::TempDir;

namespace {

RunRecord run_of(const std::string& name, size_t n = 8, const std::string& key = "") {
  RunRecord r;
  r.name = name;
  r.attrs["level"] = std::string("simulation");
  r.attrs["status"] = std::string("ok");
  if (!key.empty()) r.attrs["sweep_key"] = key;
  r.datasets["dual_residual"] = std::vector<double>(n, 0.5);
  return r;
}

std::vector<std::string> names_of(const std::vector<RunRecord>& runs) {
  std::vector<std::string> out;
  for (const auto& r : runs) out.push_back(r.name);
  return out;
}

std::string bytes_of(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

// What h5py sees: the runs the index's links reach, opened by HDF5 itself from `cwd`.
std::set<std::string> linked_runs(const std::string& path, const fs::path& cwd) {
  const fs::path here = fs::current_path();
  fs::current_path(cwd);
  std::set<std::string> out;
  {
    const h5::Guard guard;
    h5::H f = h5::open_file(path);
    h5::H runs = h5::open_group(f, "/runs", path);
    for (const auto& n : h5::link_names(runs, path))
      if (h5::link_kind(runs, n) == h5::Kind::group) out.insert(n);
  }
  fs::current_path(here);
  return out;
}

std::string store_of(const std::string& path) {
  const h5::Guard guard;
  h5::H f = h5::open_file(path);
  return std::get<std::string>(h5::read_attrs(f, path).at("store"));
}

}  // namespace

TEST(RunStore, RunFileNamesSayNumberNameAndJob) {
  const std::string name = "0012_cloth_hang_py:my.solver%x";
  const std::string key = key_digest("base|point|solver=cg|repeat=0");
  const std::string file = run_file_name(name, key);
  EXPECT_EQ(file.find('.'), file.size() - 21) << file;  // the name's own '.' is %2E: the one '.' is the key's
  StoredRun r;
  ASSERT_TRUE(parse_run_file(file, r));
  EXPECT_EQ(r.name, name);
  EXPECT_EQ(r.number, 12);
  EXPECT_EQ(r.key, key);
  ASSERT_TRUE(parse_run_file(run_file_name("0003_a", ""), r));
  EXPECT_EQ(r.key, "");
  for (const char* other : {"lock", "queue-0badf00d", ".0001_a.h5.0badf00d.1@h.tmp", "0001_a.kxyz.h5", "a.b.h5"})
    EXPECT_FALSE(parse_run_file(other, r)) << other;
}

// mv r.h5 s.h5; mv r.h5.runs s.h5.runs: every run reads from any folder at once; h5py's links
// follow once the next writer has rewritten the index.
TEST(RunStore, AFileRenamedWithItsFolderReadsFromAnyFolder) {
  TempDir d;
  const std::string r = (d.path / "r.h5").string(), s = (d.path / "s.h5").string();
  append_runs(r, {run_of("a"), run_of("b"), run_of("c")});
  fs::rename(r, s);
  fs::rename(runs_folder(r), runs_folder(s));
  fs::create_directories(d.path / "elsewhere");
  const fs::path here = fs::current_path();
  fs::current_path(d.path / "elsewhere");
  std::vector<std::string> skipped;
  const auto runs = read_runs(s, true, &skipped);
  fs::current_path(here);
  EXPECT_EQ(names_of(runs), (std::vector<std::string>{"0001_a", "0002_b", "0003_c"}));
  EXPECT_TRUE(skipped.empty()) << skipped.at(0);
  EXPECT_TRUE(linked_runs(s, d.path / "elsewhere").empty()) << "the links still name r.h5.runs";
  append_runs(s, {run_of("d")});
  EXPECT_EQ(linked_runs(s, d.path / "elsewhere").size(), 4u);
  EXPECT_EQ(linked_runs(s, "/").size(), 4u);
}

// cp -r r.h5 r.h5.runs DIR/ reads the same. The index alone reads from the folder its links name
// where that is beside it (renamed or copied without its folder), else says the folder is missing;
// a writer refuses it either way.
TEST(RunStore, ACopyWithItsFolderReadsTheSameAndAnIndexAloneSaysWhatIsMissing) {
  TempDir d;
  const std::string r = (d.path / "r.h5").string();
  append_runs(r, {run_of("a"), run_of("b")});
  fs::create_directories(d.path / "copy");
  fs::copy(r, d.path / "copy/r.h5");
  fs::copy(runs_folder(r), d.path / "copy/r.h5.runs", fs::copy_options::recursive);
  const auto copied = read_runs((d.path / "copy/r.h5").string(), true);
  EXPECT_EQ(names_of(copied), (std::vector<std::string>{"0001_a", "0002_b"}));
  EXPECT_EQ(linked_runs((d.path / "copy/r.h5").string(), "/").size(), 2u);
  fs::copy(r, d.path / "beside.h5");
  EXPECT_EQ(read_runs((d.path / "beside.h5").string()).size(), 2u);
  fs::copy(r, d.path / "copy/alone.h5");
  fs::remove_all(d.path / "copy/r.h5.runs");
  std::vector<std::string> skipped;
  EXPECT_TRUE(read_runs((d.path / "copy/alone.h5").string(), false, &skipped).empty());
  ASSERT_EQ(skipped.size(), 1u);
  EXPECT_NE(skipped[0].find("alone.h5.runs/" + store_of(r) + " is missing"), std::string::npos) << skipped[0];
  EXPECT_THROW(append_runs((d.path / "beside.h5").string(), {run_of("c")}), Error);
  EXPECT_EQ(count_runs(r), 2);
}

// --out link.h5 where link.h5 points elsewhere: the target gets the runs, the link stays a link.
TEST(RunStore, ASymlinkedOutWritesTheFileItPointsTo) {
  TempDir d;
  fs::create_directories(d.path / "real");
  const fs::path link = d.path / "link.h5", real = d.path / "real/r.h5";
  fs::create_symlink("real/r.h5", link);  // dangling until the first run
  append_runs(link.string(), {run_of("a")});
  append_runs(link.string(), {run_of("b")});
  EXPECT_TRUE(fs::is_symlink(link));
  EXPECT_TRUE(fs::is_regular_file(real));
  EXPECT_TRUE(fs::is_directory(runs_folder(real.string())));
  EXPECT_FALSE(fs::exists(runs_folder(link.string())));
  EXPECT_EQ(names_of(read_runs(link.string())), (std::vector<std::string>{"0001_a", "0002_b"}));
  EXPECT_EQ(count_runs(real.string()), 2);
}

// rm r.h5 (the runs are still in r.h5.runs/): repair rebuilds it; so does the next writer.
TEST(RunStore, AnIndexDeletedByHandIsRebuiltFromItsRunFiles) {
  TempDir d;
  const std::string r = (d.path / "r.h5").string();
  append_runs(r, {run_of("a"), run_of("b")});
  fs::remove(r);
  const RepairReport rep = repair_results(r);
  EXPECT_EQ(rep.runs, 2);
  EXPECT_EQ(rep.found.relinked.size(), 2u);
  EXPECT_EQ(names_of(read_runs(r)), (std::vector<std::string>{"0001_a", "0002_b"}));
  fs::remove(r);
  append_runs(r, {run_of("c")});
  EXPECT_EQ(names_of(read_runs(r)), (std::vector<std::string>{"0001_a", "0002_b", "0003_c"}));
  EXPECT_EQ(linked_runs(r, "/").size(), 3u);
}

// The layout before stores: an index of links to FILE.runs/<name>.<8 hex>.h5. It reads as it is;
// its first writer moves every run into a store, a run file no link names (a writer killed between
// its run file and its index) included, and removes the older files.
TEST(RunStore, AFileOfTheEarlierLayoutIsMovedIntoAStoreWithItsOrphans) {
  TempDir d;
  const std::string r = (d.path / "r.h5").string(), folder = runs_folder(r);
  fs::create_directories(folder);
  {
    const h5::Guard guard;
    for (const char* name : {"0001_a", "0002_b"}) {
      const auto image = run_file_image([&](hid_t f) {
        h5::H lcpl = h5::link_create_plist();
        h5::H g(H5Gcreate2(f, (std::string("/runs/") + name).c_str(), lcpl, H5P_DEFAULT, H5P_DEFAULT), H5Gclose);
        h5::write_attr(g, "status", std::string("ok"));
      });
      write_file_atomically(folder + "/" + name + ".0badf00d.h5", image.data(), image.size());
    }
    h5::H f = h5::create_memory_file();
    h5::H runs(H5Gcreate2(f, "runs", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), H5Gclose);
    H5Lcreate_external("r.h5.runs/0001_a.0badf00d.h5", "/runs/0001_a", runs, "0001_a", H5P_DEFAULT, H5P_DEFAULT);
    runs.reset();
    const auto image = h5::file_image(f);
    write_file_atomically(r, image.data(), image.size());
  }
  EXPECT_EQ(names_of(read_runs(r)), std::vector<std::string>{"0001_a"});
  append_runs(r, {run_of("c")});
  EXPECT_EQ(names_of(read_runs(r)), (std::vector<std::string>{"0001_a", "0002_b", "0003_c"}));
  EXPECT_FALSE(fs::exists(folder + "/0001_a.0badf00d.h5"));
  EXPECT_FALSE(fs::exists(folder + "/0002_b.0badf00d.h5"));
  EXPECT_EQ(linked_runs(r, "/").size(), 3u);
}

// A sweep's job is claimed at commit: the same sweep_key twice keeps one run.
TEST(RunStore, AJobIsKeptOnce) {
  TempDir d;
  const std::string r = (d.path / "r.h5").string();
  ResultsWriter a(r, false), b(r, false);
  EXPECT_EQ(a.add({run_of("x", 8, "base|-|solver=cg|repeat=0")}), std::vector<std::string>{"0001_x"});
  EXPECT_EQ(b.add({run_of("x", 8, "base|-|solver=cg|repeat=0")}), std::vector<std::string>{"0001_x"});
  EXPECT_EQ(b.jobs_held_already(), 1);
  b.add({run_of("x", 8, "base|-|solver=cg|repeat=1")});
  EXPECT_EQ(count_runs(r), 2);
}

// A file system whose locks fail (ENOLCK): refused, naming it, the file as it was.
TEST(RunStore, LocksThatFailAreRefusedNamingTheFileSystem) {
  TempDir d;
  const std::string r = (d.path / "r.h5").string();
  append_runs(r, {run_of("a")});
  const std::string before = bytes_of(r);
  io_fault::set("", "", "1:ENOLCK");
  try {
    append_runs(r, {run_of("b")});
    ADD_FAILURE() << "an append without a lock";
  } catch (const WriteError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("cannot lock " + r + ": the file system ("), std::string::npos) << what;
    EXPECT_NE(what.find(" at /"), std::string::npos) << what;
    EXPECT_NE(what.find("no locks available"), std::string::npos) << what;
  }
  io_fault::set("", "", "");
  EXPECT_EQ(bytes_of(r), before);
  EXPECT_EQ(count_runs(r), 1);
}

// A writer holding the lock (stopped inside its commit, say) holds up no reader.
TEST(RunStore, ReadersTakeNoLock) {
  TempDir d;
  const std::string r = (d.path / "r.h5").string();
  append_runs(r, {run_of("a"), run_of("b")});
  const FileLock held(results_lock_path(r), FileLock::Kind::exclusive, r);
  auto reading = std::async(std::launch::async, [&] { return read_runs(r, true).size(); });
  ASSERT_EQ(reading.wait_for(std::chrono::seconds(5)), std::future_status::ready) << "a reader waited for the lock";
  EXPECT_EQ(reading.get(), 2u);
}

// The index is rewritten as a copy with the new links added: after 150 single appends it links
// every run and is no more than twice the size of one built whole.
TEST(RunStore, TheIndexAddsLinksAndStaysSmall) {
  TempDir d;
  const std::string r = (d.path / "r.h5").string();
  for (int i = 0; i < 150; ++i) append_runs(r, {run_of("r", 1)});
  EXPECT_EQ(linked_runs(r, "/").size(), 150u);
  const auto grown = fs::file_size(r);
  repair_results(r);
  EXPECT_LE(grown, 2 * fs::file_size(r)) << "grown " << grown << ", whole " << fs::file_size(r);
  EXPECT_EQ(linked_runs(r, "/").size(), 150u);
}

// repair names what it found: a run file deleted by hand, a killed writer's temporary file, a
// store the index never named; and a run the index does not list yet.
TEST(RunStore, RepairSaysWhatItFound) {
  TempDir d;
  const std::string r = (d.path / "r.h5").string();
  append_runs(r, {run_of("a"), run_of("b"), run_of("c")});
  const std::string store = store_folder(r, store_of(r));
  fs::remove(store + "/0002_b.h5");
  std::ofstream(store + "/.0004_d.h5.0badf00d.1@host.tmp") << "half";
  fs::create_directories(runs_folder(r) + "/0badcafe");
  std::vector<std::string> skipped;
  EXPECT_EQ(read_runs(r, false, &skipped).size(), 2u);
  ASSERT_EQ(skipped.size(), 1u);
  EXPECT_NE(skipped[0].find("run 0002_b is listed by the index but its run file is gone"), std::string::npos) << skipped[0];
  const RepairReport rep = repair_results(r);
  EXPECT_EQ(rep.runs, 2);
  ASSERT_EQ(rep.found.dangling.size(), 1u);
  EXPECT_EQ(rep.found.dangling[0].rfind("0002_b", 0), 0u);
  EXPECT_EQ(rep.found.removed.size(), 2u);
  EXPECT_FALSE(fs::exists(runs_folder(r) + "/0badcafe"));
  skipped.clear();
  EXPECT_EQ(read_runs(r, false, &skipped).size(), 2u);
  EXPECT_TRUE(skipped.empty());
}

// A writer rewrites the index only now and then (ten times its cost apart); close() and the
// destructor bring it up to date with every run it added.
TEST(RunStore, AWritersRunsAreAllInTheIndexOnceItCloses) {
  TempDir d;
  const std::string r = (d.path / "r.h5").string(), s = (d.path / "s.h5").string();
  {
    ResultsWriter w(r, false);
    for (int i = 0; i < 30; ++i) w.add({run_of("x", 1)});
    w.close();
    EXPECT_EQ(linked_runs(r, "/").size(), 30u);
    ResultsWriter v(s, false);
    for (int i = 0; i < 30; ++i) v.add({run_of("x", 1)});
  }
  EXPECT_EQ(linked_runs(s, "/").size(), 30u);
}
