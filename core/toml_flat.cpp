#include "toml_flat.hpp"

#include "error.hpp"

#include <toml++/toml.h>

#include <algorithm>
#include <filesystem>
#include <sstream>

namespace fs = std::filesystem;

namespace xb {

namespace {
std::string node_text(const toml::node& n, const std::string& where) {
  if (auto s = n.as_string()) return s->get();
  if (auto i = n.as_integer()) return std::to_string(i->get());
  if (auto d = n.as_floating_point()) {
    std::ostringstream os;
    os.precision(17);
    os << d->get();
    return os.str();
  }
  if (auto b = n.as_boolean()) return b->get() ? "1" : "0";
  throw Error(where + ": unsupported value type (use a number or a string)");
}

void flatten(const toml::table& t, const std::string& prefix, const std::string& path, std::vector<TomlEntry>& out) {
  for (const auto& [k, v] : t) {
    const std::string key = prefix.empty() ? std::string(k.str()) : prefix + "." + std::string(k.str());
    const int line = static_cast<int>(v.source().begin.line);
    const std::string where = path + ":" + std::to_string(line);
    if (auto sub = v.as_table()) {
      flatten(*sub, key, path, out);
    } else if (auto arr = v.as_array()) {
      TomlEntry e{key, "", line, true, {}};
      for (const auto& item : *arr) e.items.push_back(node_text(item, where + ": '" + key + "'"));
      out.push_back(e);
    } else {
      out.push_back({key, node_text(v, where + ": '" + key + "'"), line, false, {}});
    }
  }
}
}  // namespace

std::vector<TomlEntry> read_toml_flat(const std::string& path) {
  std::error_code ec;
  if (fs::is_directory(path, ec)) throw Error(path + ": is a directory, not a TOML file");
  if (!fs::is_regular_file(path, ec)) throw Error(path + ": no such file");
  toml::table t;
  try {
    t = toml::parse_file(path);
  } catch (const toml::parse_error& e) {
    std::ostringstream os;
    os << path << ":" << e.source().begin.line << ":" << e.source().begin.column << ": malformed TOML: " << e.description();
    throw Error(os.str());
  }
  std::vector<TomlEntry> out;
  flatten(t, "", path, out);
  std::sort(out.begin(), out.end(), [](const TomlEntry& a, const TomlEntry& b) { return a.line < b.line; });
  return out;
}

}  // namespace xb
