#include "results_index.hpp"

#include "atomic_file.hpp"
#include "file_lock.hpp"
#include "h5io.hpp"

#include "../../core/error.hpp"

#include <algorithm>
#include <cctype>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <map>

namespace fs = std::filesystem;

namespace xb {

using namespace h5;

namespace {

// "r.h5.runs/": how the index's links name the run files (relative to its folder).
std::string link_prefix(const std::string& path) { return fs::path(path).filename().string() + ".runs/"; }

// Whether `name` (in FILE.runs/) is a run file: <anything>.<8 hex>.h5.
bool is_run_file(const std::string& name) {
  const size_t n = name.size();
  if (n < 13 || !name.ends_with(".h5") || name[n - 12] != '.') return false;
  for (size_t i = n - 11; i < n - 3; ++i)
    if (!std::isxdigit(static_cast<unsigned char>(name[i]))) return false;
  return true;
}

void write_file_attrs(hid_t file) {
  write_attr(file, "schema_version", static_cast<long long>(schema_version));
  write_attr(file, "generator", std::string("xpbd-bench"));
}

// An index in memory with these root attributes and an empty /runs.
Index index_with(const std::map<std::string, AttrValue>& attrs) {
  Index index;
  index.file = create_memory_file();
  for (const auto& [k, v] : attrs) write_attr(index.file, k, v);
  index.runs = H(H5Gcreate2(index.file, "runs", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), H5Gclose);
  check_id(index.runs, "create group /runs");
  if (auto it = attrs.find("writer"); it != attrs.end())
    if (auto* s = std::get_if<std::string>(&it->second)) index.writer = *s;
  return index;
}

// The value of a soft or external link: (target file or "", target object).
std::pair<std::string, std::string> link_value(hid_t loc, const std::string& name, const H5L_info_t& info,
                                               const std::string& where) {
  std::vector<char> buf(info.u.val_size + 1, '\0');
  if (H5Lget_val(loc, name.c_str(), buf.data(), buf.size(), H5P_DEFAULT) < 0) throw Error(where + ": cannot read link " + name);
  if (info.type == H5L_TYPE_SOFT) return {"", buf.data()};
  const char *file = nullptr, *object = nullptr;
  unsigned flags = 0;
  if (H5Lunpack_elink_val(buf.data(), info.u.val_size, &flags, &file, &object) < 0 || !file || !object)
    throw Error(where + ": cannot read external link " + name);
  return {file, object};
}

// Copies the link `name` of `from` into `to` as it is (a hard link: the object, copied).
// Returns the external link's target file ("" for other links).
std::string copy_link(hid_t from, hid_t to, const std::string& name, const std::string& where) {
  H5L_info_t info;
  if (H5Lget_info(from, name.c_str(), &info, H5P_DEFAULT) < 0) throw Error(where + ": cannot read link " + name);
  if (info.type == H5L_TYPE_HARD) {
    check(H5Ocopy(from, name.c_str(), to, name.c_str(), H5P_DEFAULT, H5P_DEFAULT), "copy " + name);
    return "";
  }
  if (info.type != H5L_TYPE_SOFT && info.type != H5L_TYPE_EXTERNAL) throw Error(where + ": link " + name + " of an unknown kind");
  const auto [file, object] = link_value(from, name, info, where);
  if (info.type == H5L_TYPE_SOFT) {
    check(H5Lcreate_soft(object.c_str(), to, name.c_str(), H5P_DEFAULT, H5P_DEFAULT), "link " + name);
    return "";
  }
  check(H5Lcreate_external(file.c_str(), object.c_str(), to, name.c_str(), H5P_DEFAULT, H5P_DEFAULT), "link " + name);
  return file;
}

// Whether `name` under `loc` is a group stored in this file (not through a link to another).
bool inline_group(hid_t loc, const std::string& name) {
  H5L_info_t info;
  if (H5Lget_info(loc, name.c_str(), &info, H5P_DEFAULT) < 0 || info.type != H5L_TYPE_HARD) return false;
  H5O_info_t oi;
  return H5Oget_info_by_name2(loc, name.c_str(), &oi, H5O_INFO_BASIC, H5P_DEFAULT) >= 0 && oi.type == H5O_TYPE_GROUP;
}

}  // namespace

std::string runs_folder(const std::string& path) { return path + ".runs"; }
std::string results_lock_path(const std::string& path) { return runs_folder(path) + "/lock"; }

RunFiles::~RunFiles() {
  std::error_code ec;
  for (const auto& f : files_) fs::remove(f, ec);
}

std::string RunFiles::write(const std::string& name, const std::function<void(hid_t)>& fill) {
  std::string base = name;
  for (char& c : base)
    if (c == '/') c = '_';
  const std::string file = base + "." + random_hex8() + ".h5";
  std::vector<char> image;
  {
    H f = create_memory_file();
    write_file_attrs(f);
    fill(f);
    image = file_image(f);
  }
  TmpFile out(runs_folder(path_) + "/" + file, path_, true);
  out.write(image.data(), image.size());
  out.commit();
  files_.push_back(out.target());
  return link_prefix(path_) + file;
}

Index new_index(const std::string& writer) {
  std::map<std::string, AttrValue> attrs{{"schema_version", static_cast<long long>(schema_version)},
                                         {"generator", std::string("xpbd-bench")}};
  if (!writer.empty()) attrs["writer"] = writer;
  return index_with(attrs);
}

Index carry_index(const std::string& path, RunFiles& made) {
  H old = open_file(path);
  if (link_kind(old, "/runs") != Kind::group)
    throw Error(path + ": not an xpbd-bench results file (no group /runs); refusing to append to it");
  Index index = index_with(read_attrs(old, path + ": root"));
  for (const auto& name : link_names(old, path))
    if (name != "runs") copy_link(old, index.file, name, path);
  H runs = open_group(old, "/runs", path);
  const std::string prefix = link_prefix(path);
  for (const auto& name : link_names(runs, path + ": /runs")) {
    if (inline_group(runs, name)) {  // moved out to a run file once: later appends do not copy it
      link_run(index, name, made.write(name, [&](hid_t f) {
        H lcpl = link_create_plist();
        check(H5Ocopy(runs, name.c_str(), f, ("/runs/" + name).c_str(), H5P_DEFAULT, lcpl), "copy run " + name);
      }));
      continue;
    }
    const std::string file = copy_link(runs, index.runs, name, path + ": /runs");
    index.names.push_back(name);
    if (file.starts_with(prefix)) index.linked.insert(file.substr(prefix.size()));
  }
  return index;
}

int next_run_number(const Index& index) {
  long long last = static_cast<long long>(index.names.size());
  for (const auto& n : index.names) {
    const size_t cut = n.find('_');
    if (cut == 0 || cut == std::string::npos || cut > 9) continue;
    bool digits = true;
    for (size_t i = 0; i < cut; ++i) digits = digits && std::isdigit(static_cast<unsigned char>(n[i]));
    if (digits) last = std::max(last, std::stoll(n.substr(0, cut)));
  }
  return static_cast<int>(last + 1);
}

void link_run(Index& index, const std::string& name, const std::string& file) {
  check(H5Lcreate_external(file.c_str(), ("/runs/" + name).c_str(), index.runs, name.c_str(), H5P_DEFAULT, H5P_DEFAULT),
        "link run " + name);
  index.names.push_back(name);
  index.linked.insert(fs::path(file).filename().string());
}

void write_run(hid_t file, const RunRecord& r, const std::string& name) {
  H lcpl = link_create_plist();
  const std::string path = "/runs/" + name;
  if (H5Lexists(file, "/runs", H5P_DEFAULT) > 0 && H5Lexists(file, path.c_str(), H5P_DEFAULT) > 0)
    throw Error("results file already has a run named '" + name + "'");
  H g(H5Gcreate2(file, path.c_str(), lcpl, H5P_DEFAULT, H5P_DEFAULT), H5Gclose);
  check_id(g, "create group " + path);
  for (const auto& [k, v] : r.attrs) write_attr(g, k, v);
  for (const auto& [k, v] : r.datasets) write_dataset(g, k, v);
}

void commit_index(const std::string& path, const Index& index) {
  const std::vector<char> image = file_image(index.file);
  TmpFile out(path, path, true);
  out.write(image.data(), image.size());
  out.commit();
}

namespace {
// Whether the file starts with HDF5's signature (at 0: files we write have no user block).
bool looks_hdf5(const fs::path& p) {
  char sig[8] = {};
  FILE* f = std::fopen(p.c_str(), "rb");
  if (!f) return false;
  const bool ok = std::fread(sig, 1, 8, f) == 8 && std::memcmp(sig, "\x89HDF\r\n\x1a\n", 8) == 0;
  std::fclose(f);
  return ok;
}

// The run files of FILE.runs/ that another results file in FILE's folder links (a copy of the
// index, or FILE renamed): a replaced FILE must not take them with it.
std::set<std::string> linked_by_others(const std::string& path) {
  std::set<std::string> linked;
  const fs::path dir = fs::path(path).parent_path().empty() ? fs::path(".") : fs::path(path).parent_path();
  const std::string prefix = link_prefix(path);
  std::error_code ec;
  for (fs::directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec)) {
    std::error_code same;
    if (!it->is_regular_file(same) || fs::equivalent(it->path(), path, same) || !looks_hdf5(it->path())) continue;
    try {
      H f = open_file(it->path().string());
      if (link_kind(f, "/runs") != Kind::group) continue;
      H runs = open_group(f, "/runs", it->path().string());
      for (const auto& name : link_names(runs, it->path().string())) {
        H5L_info_t info;
        if (H5Lget_info(runs, name.c_str(), &info, H5P_DEFAULT) < 0 || info.type != H5L_TYPE_EXTERNAL) continue;
        const std::string file = link_value(runs, name, info, it->path().string()).first;
        if (file.starts_with(prefix)) linked.insert(file.substr(prefix.size()));
      }
    } catch (const Error&) {  // a damaged file links nothing we keep for it
    }
  }
  return linked;
}
}  // namespace

void collect_garbage(const std::string& path, const Index& index, bool replaced) {
  remove_stale_temporaries(path, true);
  std::set<std::string> keep = index.linked;
  if (replaced) keep.merge(linked_by_others(path));
  std::error_code ec;
  for (fs::directory_iterator it(runs_folder(path), ec), end; !ec && it != end; it.increment(ec)) {
    const std::string name = it->path().filename().string();
    std::error_code rm;
    if (name.ends_with(".tmp") || (replaced && is_run_file(name) && !keep.count(name))) fs::remove(it->path(), rm);
    if (name.starts_with("queue-")) remove_unused_counter(it->path().string());  // a killed sweep's (file_lock.hpp)
  }
}

std::vector<char> packed_image(const std::string& src, std::vector<std::string>& skipped) {
  H in = open_file(src);
  const Kind k = link_kind(in, "/runs");
  if (k != Kind::group) throw Error(src + ": not an xpbd-bench results file (/runs is " + kind_text(k) + ")");
  H in_runs = open_group(in, "/runs", src);
  H out = create_memory_file();
  for (const auto& [key, v] : read_attrs(in, src + ": root"))
    if (key != "writer") write_attr(out, key, v);
  H out_runs(H5Gcreate2(out, "runs", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), H5Gclose);
  check_id(out_runs, "create group /runs");
  for (const auto& name : link_names(in_runs, src + ": /runs")) {
    const Kind rk = link_kind(in_runs, name);
    if (rk != Kind::group) {
      skipped.push_back(src + ": run " + name + " is " + kind_text(rk) + ", not a run group");
      continue;
    }
    // Through the link: the run's group itself, with everything in it.
    check(H5Ocopy(in_runs, name.c_str(), out_runs, name.c_str(), H5P_DEFAULT, H5P_DEFAULT), "copy run " + name);
  }
  return file_image(out);
}

}  // namespace xb
