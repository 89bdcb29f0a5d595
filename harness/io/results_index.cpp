#include "results_index.hpp"

#include "atomic_file.hpp"
#include "h5io.hpp"

#include "../../core/error.hpp"

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <iterator>

namespace fs = std::filesystem;

namespace xb {

using namespace h5;

namespace {

// Root attributes the index keeps up to date itself; the others are carried as they are.
bool own_attr(const std::string& key) { return key == "store" || key == "links_to" || key == "runs_indexed"; }

std::string text_attr(const std::map<std::string, AttrValue>& attrs, const std::string& key) {
  auto it = attrs.find(key);
  const auto* s = it == attrs.end() ? nullptr : std::get_if<std::string>(&it->second);
  return s ? *s : "";
}

// An attribute set in place when it exists with the same type (no space left behind in the file
// by a delete and a create: the index is updated over and over), else made anew.
void set_attr(hid_t file, const char* key, const AttrValue& v) {
  if (H5Aexists(file, key) > 0) {
    H a(H5Aopen(file, key, H5P_DEFAULT), H5Aclose);
    H t(a < 0 ? H5I_INVALID_HID : H5Aget_type(a), H5Tclose);
    if (const auto* n = std::get_if<long long>(&v); n && t >= 0 && H5Tget_class(t) == H5T_INTEGER && H5Tget_size(t) == sizeof(long long)) {
      check(H5Awrite(a, H5T_NATIVE_LLONG, n), std::string("write attribute ") + key);
      return;
    }
    if (const auto* s = std::get_if<std::string>(&v); s && a >= 0 && read_attr(a, key) == v) return;
    a.reset();
    check(H5Adelete(file, key), std::string("replace attribute ") + key);
  }
  write_attr(file, key, v);
}

void set_own_attrs(hid_t file, const IndexHead& head, const std::string& prefix, long long top) {
  set_attr(file, "store", head.store);
  set_attr(file, "links_to", prefix);
  set_attr(file, "runs_indexed", top);
}

// /runs/<name> → <prefix>/<file>, object /runs/<name>; a name taken already (two files of one run
// name) or holding a '/' links nothing: readers list the folder, not the links.
void link_run(hid_t runs, const StoredRun& r, const std::string& prefix) {
  if (r.name.find('/') != std::string::npos || H5Lexists(runs, r.name.c_str(), H5P_DEFAULT) > 0) return;
  check(H5Lcreate_external((prefix + "/" + r.file).c_str(), ("/runs/" + r.name).c_str(), runs, r.name.c_str(), H5P_DEFAULT,
                           H5P_DEFAULT),
        "link run " + r.name);
}

long long top_number(const std::vector<StoredRun>& runs) {
  long long top = 0;
  for (const auto& r : runs) top = std::max(top, r.number);
  return top;
}

std::vector<char> whole_index(const IndexHead& head, const std::vector<StoredRun>& runs, const std::string& prefix) {
  H f = create_memory_file();
  for (const auto& [k, v] : head.attrs)
    if (!own_attr(k)) write_attr(f, k, v);
  set_own_attrs(f, head, prefix, top_number(runs));
  H g(H5Gcreate2(f, "runs", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), H5Gclose);
  check_id(g, "create group /runs");
  for (const auto& r : runs) link_run(g, r, prefix);
  return file_image(f);
}

// The index on disk with the runs after head.indexed added; empty when it must be built whole.
std::vector<char> added_index(const std::string& path, const IndexHead& head, const std::vector<StoredRun>& runs,
                              const std::string& prefix) {
  if (head.kind != IndexHead::Kind::store || head.links_to != prefix) return {};
  std::ifstream in(path, std::ios::binary);
  const std::vector<char> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (bytes.empty()) return {};
  H f = open_memory_image(bytes);
  if (f < 0 || H5Lexists(f, "runs", H5P_DEFAULT) <= 0) return {};
  {
    H g(H5Gopen2(f, "runs", H5P_DEFAULT), H5Gclose);
    if (g < 0) return {};
    for (const auto& r : runs)
      if (r.number > head.indexed) link_run(g, r, prefix);
  }
  set_own_attrs(f, head, prefix, std::max(head.indexed, top_number(runs)));
  std::vector<char> image = file_image(f);
  // HDF5 does not reuse the space an update frees: rebuilt whole once the file is twice the size
  // of a whole one (estimated from its links: ~50 bytes and their names each).
  size_t whole = 8192;
  for (const auto& r : runs) whole += 48 + 2 * r.name.size() + r.file.size() + prefix.size() + 10;
  return image.size() > 2 * whole ? std::vector<char>{} : image;
}

}  // namespace

IndexHead read_index_head(const std::string& path) {
  IndexHead head;
  std::error_code ec;
  if (!fs::exists(path, ec)) return head;
  H f = open_file(path);
  const Kind k = link_kind(f, "/runs");
  if (k == Kind::missing) throw Error(path + ": not an xpbd-bench results file (no group /runs)");
  if (k != Kind::group) throw Error(path + ": /runs is " + std::string(kind_text(k)) + ", expected the group of runs");
  head.attrs = read_attrs(f, path + ": root");
  head.store = text_attr(head.attrs, "store");
  head.writer = text_attr(head.attrs, "writer");
  head.links_to = text_attr(head.attrs, "links_to");
  if (auto it = head.attrs.find("runs_indexed"); it != head.attrs.end())
    if (const auto* n = std::get_if<long long>(&it->second)) head.indexed = *n;
  head.kind = is_store_name(head.store) ? IndexHead::Kind::store : IndexHead::Kind::older;
  return head;
}

IndexHead new_index_head(const std::string& store, const std::string& writer) {
  IndexHead head;
  head.kind = IndexHead::Kind::store;
  head.store = store;
  head.writer = writer;
  head.attrs = {{"schema_version", static_cast<long long>(schema_version)},
                {"generator", std::string("xpbd-bench")},
                {"writer", writer}};
  return head;
}

std::string store_folder_of(const std::string& path, const IndexHead& head) {
  const std::string own = store_folder(path, head.store);
  std::error_code ec;
  if (fs::is_directory(own, ec) || head.links_to.empty() || fs::path(head.links_to).is_absolute()) return own;
  const fs::path linked = fs::path(path).parent_path() / head.links_to;
  return fs::is_directory(linked, ec) ? linked.string() : own;
}

std::string links_prefix(const std::string& path, const std::string& store) {
  return fs::path(runs_folder(path)).filename().string() + "/" + store;
}

long long write_index(const std::string& path, const IndexHead& head, const std::vector<StoredRun>& runs, bool whole) {
  const std::string prefix = links_prefix(path, head.store);
  std::vector<char> image;
  if (!whole) image = added_index(path, head, runs, prefix);
  if (image.empty()) image = whole_index(head, runs, prefix);
  TmpFile out(path, path, true);
  out.write(image.data(), image.size());
  out.commit();
  return std::max(whole ? 0 : head.indexed, top_number(runs));
}

std::vector<IndexMember> index_members(hid_t runs, const std::string& where) {
  struct Ctx {
    std::vector<IndexMember> out;
    std::string error;
  } ctx;
  const herr_t e = H5Literate(
      runs, H5_INDEX_NAME, H5_ITER_INC, nullptr,
      [](hid_t g, const char* name, const H5L_info_t* info, void* data) -> herr_t {
        auto* c = static_cast<Ctx*>(data);
        IndexMember m;
        m.name = name;
        if (info->type == H5L_TYPE_EXTERNAL) {
          std::vector<char> buf(info->u.val_size + 1, '\0');
          const char *file = nullptr, *object = nullptr;
          unsigned flags = 0;
          if (H5Lget_val(g, name, buf.data(), buf.size(), H5P_DEFAULT) < 0 ||
              H5Lunpack_elink_val(buf.data(), info->u.val_size, &flags, &file, &object) < 0 || !file || !object) {
            c->error = std::string("cannot read external link ") + name;
            return -1;
          }
          m.kind = IndexMember::Kind::external;
          m.file = file;
          m.object = object;
        } else if (info->type == H5L_TYPE_HARD) {
          H5O_info_t oi;
          if (H5Oget_info_by_name2(g, name, &oi, H5O_INFO_BASIC, H5P_DEFAULT) >= 0 && oi.type == H5O_TYPE_GROUP)
            m.kind = IndexMember::Kind::group;
        }
        c->out.push_back(std::move(m));
        return 0;
      },
      &ctx);
  if (!ctx.error.empty()) throw Error(where + ": " + ctx.error);
  if (e < 0) throw Error(where + ": cannot list its members");
  return ctx.out;
}

std::string link_target(const std::string& path, const std::string& file) {
  const fs::path f(file);
  if (f.is_absolute()) return file;
  const fs::path dir = fs::path(path).parent_path();
  const std::string first = f.begin() == f.end() ? "" : f.begin()->string();
  if (first.size() > 5 && first.ends_with(".runs"))
    return (fs::path(runs_folder(path)) / f.lexically_relative(first)).string();
  return (dir / f).string();
}

}  // namespace xb
