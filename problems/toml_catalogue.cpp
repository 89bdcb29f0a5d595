#include "toml_catalogue.hpp"

#include "../core/error.hpp"

#include <algorithm>
#include <cstdlib>
#include <filesystem>

#ifndef XB_SOURCE_DIR
#define XB_SOURCE_DIR "."
#endif

namespace fs = std::filesystem;

namespace xb {

std::string TomlCatalogue::dir() const {
  if (const char* d = std::getenv(env.c_str())) return d;
  return std::string(XB_SOURCE_DIR) + "/problems/" + folder;
}

std::vector<std::string> TomlCatalogue::names() const {
  std::vector<std::string> v;
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(dir(), ec))
    if (e.path().extension() == ".toml") v.push_back(e.path().stem().string());
  std::sort(v.begin(), v.end());
  return v;
}

std::string TomlCatalogue::resolve(const std::string& name_or_file) const {
  if (name_or_file.find('/') != std::string::npos || name_or_file.ends_with(".toml")) {
    std::error_code ec;
    if (fs::is_directory(name_or_file, ec)) throw Error(what + " file '" + name_or_file + "' is a directory");
    if (!fs::is_regular_file(name_or_file, ec)) throw Error(what + " file '" + name_or_file + "' does not exist");
    return name_or_file;
  }
  const auto known = names();
  if (std::find(known.begin(), known.end(), name_or_file) == known.end()) {
    std::string valid;
    for (const auto& n : known) valid += (valid.empty() ? "" : ", ") + n;
    throw Error("unknown " + what + " '" + name_or_file + "' (valid: " + valid + ")");
  }
  return dir() + "/" + name_or_file + ".toml";
}

}  // namespace xb
