#include "state_io.hpp"

#include "../cli/run_setup.hpp"
#include "run_record.hpp"
#include "h5io.hpp"

#include "../../core/error.hpp"

#include <filesystem>

namespace fs = std::filesystem;

namespace xb {

using h5::H;

void write_state(const std::string& path, const SimState& s, const Params& p) {
  const std::string tmp = path + ".tmp";
  if (fs::path(path).has_parent_path()) fs::create_directories(fs::path(path).parent_path());
  {
    H file(H5Fcreate(tmp.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT), H5Fclose);
    if (file < 0) throw Error("--save-state: cannot create " + tmp);
    RunRecord r;  // the parameters and provenance, as for a run
    add_provenance(r, p);
    for (const auto& [k, v] : r.attrs) h5::write_attr(file, k, v);
    h5::write_attr(file, "kind", std::string("state"));
    h5::write_attr(file, "generator", std::string("xpbd-bench"));
    h5::write_attr(file, "frame", static_cast<long long>(s.frame));
    h5::write_attr(file, "particles", static_cast<long long>(s.x.cols()));
    h5::write_dataset(file, "positions", std::vector<double>(s.x.data(), s.x.data() + s.x.size()));
    h5::write_dataset(file, "velocities", std::vector<double>(s.v.data(), s.v.data() + s.v.size()));
    h5::check(H5Fflush(file, H5F_SCOPE_GLOBAL), "flush");
  }
  fs::rename(tmp, path);
}

SimState read_state(const std::string& path) {
  h5::silence_errors();
  if (!fs::is_regular_file(path)) throw Error("--load-state: " + path + ": no such file");
  H file(H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT), H5Fclose);
  if (file < 0) throw Error("--load-state: " + path + ": not an HDF5 file");
  auto attr = [&](const char* name) {
    if (H5Aexists(file, name) <= 0) throw Error("--load-state: " + path + ": not a state file (no attribute " + name + ")");
    H a(H5Aopen(file, name, H5P_DEFAULT), H5Aclose);
    return h5::read_attr(a);
  };
  const AttrValue kind = attr("kind");
  if (!std::holds_alternative<std::string>(kind) || std::get<std::string>(kind) != "state")
    throw Error("--load-state: " + path + ": not a state file (kind is not \"state\"; write one with run --save-state)");
  SimState s;
  s.frame = static_cast<int>(std::get<long long>(attr("frame")));
  const long long n = std::get<long long>(attr("particles"));
  for (const char* name : {"positions", "velocities"}) {
    if (H5Lexists(file, name, H5P_DEFAULT) <= 0) throw Error("--load-state: " + path + ": no dataset " + name);
    H d(H5Dopen2(file, name, H5P_DEFAULT), H5Dclose);
    const auto v = std::get<std::vector<double>>(h5::read_dataset(d));
    if (static_cast<long long>(v.size()) != 3 * n)
      throw Error("--load-state: " + path + ": " + name + " has " + std::to_string(v.size()) + " entries, expected 3 x " +
                  std::to_string(n));
    (name[0] == 'p' ? s.x : s.v) = Eigen::Map<const Eigen::Matrix3Xd>(v.data(), 3, n);
  }
  return s;
}

}  // namespace xb
