// What every fuzz target shares: the readers take paths, so each input is written to a file in a
// per-process folder (on /dev/shm when it exists: no disk I/O per execution), and a reader may
// end only in xb::Error. Any other exception is a finding (the CLI would print "internal error").
#pragma once

#include "core/error.hpp"

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <fstream>
#include <string>
#include <string_view>
#include <unistd.h>

namespace xb_fuzz {

// The per-process folder, removed at exit.
struct WorkDir {
  std::string path;
  WorkDir() {
    const char* base = std::filesystem::is_directory("/dev/shm") ? "/dev/shm" : "/tmp";
    path = std::string(base) + "/xb-fuzz-" + std::to_string(getpid());
    std::filesystem::create_directories(path);
  }
  ~WorkDir() {
    std::error_code ec;
    std::filesystem::remove_all(path, ec);
  }
};

inline const std::string& work_dir() {
  static const WorkDir dir;
  return dir.path;
}

// Writes bytes to work_dir()/name and returns the path.
inline std::string write_file(const std::string& name, std::string_view bytes) {
  const std::string path = work_dir() + "/" + name;
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  if (!out) {
    std::fprintf(stderr, "fuzz: cannot write %s\n", path.c_str());
    std::abort();
  }
  return path;
}

inline std::string_view as_text(const uint8_t* data, size_t size) {
  return {reinterpret_cast<const char*>(data), size};
}

// Runs a reader: xb::Error is the expected way to refuse an input; anything else aborts, so
// libFuzzer records the input.
template <class F>
void expect_clean(F&& read) {
  try {
    read();
  } catch (const xb::Error&) {
  } catch (const std::exception& e) {
    std::fprintf(stderr, "fuzz: not an xb::Error: %s\n", e.what());
    std::abort();
  }
}

}  // namespace xb_fuzz
