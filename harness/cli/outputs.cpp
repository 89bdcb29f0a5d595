#include "outputs.hpp"

#include "../io/atomic_file.hpp"
#include "../io/h5io.hpp"
#include "../io/recorder.hpp"

#include "../../core/error.hpp"
#include "../../problems/meshes/real_meshes.hpp"

#include <unistd.h>

#include <cerrno>

#include <filesystem>

namespace fs = std::filesystem;

namespace xb {

std::vector<std::string> mesh_inputs(const Params& p) {
  const std::string& m = p.mesh;
  if (m.empty() || m == "bar" || m == "ball") return {};
  if (is_named_mesh(m)) {
    const std::string base = mesh_cache_dir() + "/" + m.substr(0, m.find(':')) + "_" + m.substr(m.find(':') + 1);
    return {base + ".node", base + ".ele"};
  }
  const fs::path path(m);
  if (path.extension() == ".node" || path.extension() == ".ele") {
    fs::path node = path, ele = path;
    return {node.replace_extension(".node").string(), ele.replace_extension(".ele").string()};
  }
  return {m};
}

namespace {
// By identity when both exist (links, "./", hard links), else by their canonical paths.
bool same_file(const std::string& a, const std::string& b) {
  std::error_code ec, ec2;
  if (fs::exists(a, ec) && fs::exists(b, ec)) return fs::equivalent(a, b, ec) && !ec;
  const fs::path ca = fs::weakly_canonical(a, ec), cb = fs::weakly_canonical(b, ec2);
  return !ec && !ec2 && ca == cb;
}

void check_not_input(const std::string& what, const std::string& out, const std::vector<std::string>& inputs) {
  for (const auto& in : inputs)
    if (same_file(out, in))
      throw Error(what + " " + out + " is an input of this command; it would be overwritten: write elsewhere");
}

// The folder of output `out` (`what` names both in messages): made now; a failure, or one that
// cannot be written in, is a WriteError naming out.
void make_folder(const std::string& what, const std::string& out, const fs::path& dir) {
  if (dir.empty()) return;
  std::error_code ec;
  if (fs::exists(dir, ec) && !fs::is_directory(dir, ec)) throw Error(what + ": " + dir.string() + " is not a directory");
  fs::create_directories(dir, ec);
  if (ec || !fs::is_directory(dir))
    throw WriteError(out, ec ? ec.value() : ENOTDIR, what + ": cannot create directory " + dir.string() + (ec ? ": " + ec.message() : ""));
  if (::access(dir.c_str(), W_OK | X_OK) != 0) {
    const int e = errno;
    throw WriteError(out, e, what + ": cannot write in directory " + dir.string() + ": " + errno_text(e));
  }
}
}  // namespace

void check_output(const std::string& command, const std::string& flag, const std::string& out,
                  const std::vector<std::string>& inputs) {
  const std::string what = command + ": " + flag + " " + out;
  std::error_code ec;
  if (out.empty() || fs::path(out).filename().empty() || fs::is_directory(out, ec))
    throw Error(what + " is a directory; give a file name");
  check_not_input(command + ": " + flag, out, inputs);
  make_folder(what, out, fs::path(out).parent_path());
}

void check_output_dir(const std::string& command, const std::string& flag, const std::string& dir,
                      const std::vector<std::string>& inputs) {
  for (const auto& in : inputs)
    if (same_file(dir, in)) throw Error(command + ": " + flag + " " + dir + " is an input of this command");
  make_folder(command + ": " + flag, dir, dir);
}

bool is_results_file(const std::string& path) {
  std::error_code ec;
  if (!fs::is_regular_file(path, ec)) return false;
  const h5::Guard guard;  // h5handle.hpp
  h5::silence_errors();
  const h5::H f(H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT), H5Fclose);
  return f >= 0 && H5Lexists(f, "/runs", H5P_DEFAULT) > 0;
}

void check_replaceable(const std::string& command, const std::string& out) {
  std::error_code ec;
  if (fs::exists(out, ec) && !is_results_file(out))
    throw Error(command + ": --out " + out + " exists and is not an xpbd-bench results file (it would be replaced); "
                "remove it or write elsewhere");
}

std::string append_command_run(const std::string& command, ResultsWriter& out, const RunRecord& run, int kept,
                               const std::string& hint) {
  try {
    return out.add({run}).at(0);
  } catch (const WriteError& e) {
    throw command_write_error(command, e, "it", kept, hint);
  }
}

ResultsWriter command_writer(const std::string& command, const std::string& out, bool append) {
  std::error_code ec;
  if (!append)
    check_replaceable(command, out);
  else if (fs::exists(out, ec) && !is_results_file(out))
    throw Error(command + ": --out " + out + " exists and is not an xpbd-bench results file; --append only adds to one");
  return ResultsWriter(out, !append);
}

void close_command_writer(const std::string& command, ResultsWriter& out) {
  try {
    out.close();
  } catch (const WriteError& e) {
    throw WriteError(e.path, e.err,
                     command + ": " + e.what() + "; its " + std::to_string(out.runs_in_file()) +
                         " runs are kept (report and xpbd_bench.read read them): its index, what h5py reads, is brought "
                         "up to date by the next writer or `xpbd-bench repair`");
  }
}

WriteError command_write_error(const std::string& command, const WriteError& e, const std::string& holder, int kept,
                               const std::string& hint) {
  std::string line = command + ": " + e.what();
  if (kept > 0)
    line += "; " + holder + " holds the " + std::to_string(kept) + (kept == 1 ? " run" : " runs") + " finished before";
  return WriteError(e.path, e.err, line + hint);
}

}  // namespace xb
