#include "run_store.hpp"

#include "atomic_file.hpp"
#include "h5io.hpp"

#include <dirent.h>

#include <algorithm>
#include <cctype>
#include <cstdio>
#include <filesystem>

namespace fs = std::filesystem;

namespace xb {

namespace {
bool all_hex(const std::string& s, size_t from, size_t n) {
  if (s.size() < from + n) return false;
  for (size_t i = from; i < from + n; ++i)
    if (!std::isxdigit(static_cast<unsigned char>(s[i])) || std::isupper(static_cast<unsigned char>(s[i]))) return false;
  return true;
}

// Letters, digits and _+:=,@- stand for themselves in a file name; anything else (the '.' that
// separates the key, '/', '%') is %XX.
bool plain(char c) {
  return std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '+' || c == ':' || c == '=' || c == ',' ||
         c == '@' || c == '-';
}

std::string encode(const std::string& name) {
  std::string out;
  for (char c : name) {
    if (plain(c)) {
      out += c;
      continue;
    }
    char b[4];
    std::snprintf(b, sizeof b, "%%%02X", static_cast<unsigned char>(c));
    out += b;
  }
  return out;
}

bool decode(const std::string& text, std::string& out) {
  out.clear();
  for (size_t i = 0; i < text.size(); ++i) {
    if (text[i] != '%') {
      if (!plain(text[i])) return false;
      out += text[i];
      continue;
    }
    if (i + 2 >= text.size() || !std::isxdigit(static_cast<unsigned char>(text[i + 1])) ||
        !std::isxdigit(static_cast<unsigned char>(text[i + 2])))
      return false;
    out += static_cast<char>(std::stoi(text.substr(i + 1, 2), nullptr, 16));
    i += 2;
  }
  return !out.empty();
}
}  // namespace

std::string runs_folder(const std::string& path) { return path + ".runs"; }
std::string results_lock_path(const std::string& path) { return runs_folder(path) + "/lock"; }
std::string store_folder(const std::string& path, const std::string& store) { return runs_folder(path) + "/" + store; }
bool is_store_name(const std::string& name) { return name.size() == 8 && all_hex(name, 0, 8); }
std::string new_store_name() { return random_hex8(); }

std::string resolve_results_path(const std::string& path) {
  fs::path p(path);
  std::error_code ec;
  bool followed = false;
  for (int hops = 0; hops < 40 && fs::is_symlink(p, ec); ++hops) {
    const fs::path target = fs::read_symlink(p, ec);
    if (ec) break;
    p = target.is_absolute() ? target : p.parent_path() / target;
    followed = true;
  }
  return followed ? p.lexically_normal().string() : path;
}

std::string run_file_name(const std::string& name, const std::string& key) {
  return encode(name) + (key.empty() ? "" : ".k" + key) + ".h5";
}

bool parse_run_file(const std::string& file, StoredRun& out) {
  if (file.empty() || file[0] == '.' || !file.ends_with(".h5")) return false;
  std::string stem = file.substr(0, file.size() - 3), key;
  const size_t dot = stem.find('.');
  if (dot != std::string::npos) {  // the only '.' a name keeps is the key's
    if (stem.size() - dot != 18 || stem[dot + 1] != 'k' || !all_hex(stem, dot + 2, 16)) return false;
    key = stem.substr(dot + 2);
    stem.resize(dot);
  }
  StoredRun r;
  if (!decode(stem, r.name)) return false;
  size_t digits = 0;
  while (digits < r.name.size() && std::isdigit(static_cast<unsigned char>(r.name[digits]))) ++digits;
  if (digits > 0 && digits <= 15 && digits < r.name.size() && r.name[digits] == '_') r.number = std::stoll(r.name.substr(0, digits));
  r.file = file;
  r.key = key;
  out = std::move(r);
  return true;
}

std::string key_digest(const std::string& sweep_key) {
  unsigned long long h = 1469598103934665603ULL;
  for (unsigned char c : sweep_key) {
    h ^= c;
    h *= 1099511628211ULL;
  }
  char b[17];
  std::snprintf(b, sizeof b, "%016llx", h);
  return b;
}

std::string numbered(long long number, const std::string& name) {
  char head[24];
  std::snprintf(head, sizeof head, "%04lld_", number);
  return head + name;
}

StoreListing list_store(const std::string& folder) {
  StoreListing out;
  DIR* dir = ::opendir(folder.c_str());
  if (!dir) return out;
  out.exists = true;
  while (const dirent* e = ::readdir(dir)) {
    const std::string name = e->d_name;
    StoredRun r;
    if (parse_run_file(name, r)) {
      out.last = std::max(out.last, r.number);
      out.runs.push_back(std::move(r));
    } else if (name.size() > 4 && name[0] == '.' && name.ends_with(".tmp")) {
      out.temporaries.push_back(folder + "/" + name);
    }
  }
  ::closedir(dir);
  std::sort(out.runs.begin(), out.runs.end(),
            [](const StoredRun& a, const StoredRun& b) { return a.number != b.number ? a.number < b.number : a.name < b.name; });
  return out;
}

std::vector<char> run_file_image(const std::function<void(hid_t)>& fill) {
  h5::H f = h5::create_memory_file();
  h5::write_attr(f, "schema_version", static_cast<long long>(schema_version));
  h5::write_attr(f, "generator", std::string("xpbd-bench"));
  fill(f);
  return h5::file_image(f);
}

bool commit_run_file(const std::string& folder, const std::string& file, const std::vector<char>& image,
                     const std::string& shown) {
  TmpFile out(folder + "/" + file, shown, true);
  out.write(image.data(), image.size());
  return out.commit_new();
}

}  // namespace xb
