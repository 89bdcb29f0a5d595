#include "state_io.hpp"

#include "run_record.hpp"
#include "atomic_file.hpp"
#include "h5io.hpp"
#include "system_io.hpp"

#include "../../core/error.hpp"

#include <filesystem>
#include <optional>

namespace fs = std::filesystem;

namespace xb {

using h5::H;

void write_state(const std::string& path, const SimState& s, const Params& p) {
  std::vector<char> image;
  {
    const h5::Guard guard;  // h5handle.hpp
    H file = h5::create_memory_file();  // written by us, whole or not at all (h5io.hpp)
    RunRecord r;  // the parameters and provenance, as for a run
    add_provenance(r, p);
    for (const auto& [k, v] : r.attrs) h5::write_attr(file, k, v);
    h5::write_attr(file, "kind", std::string("state"));
    h5::write_attr(file, "generator", std::string("xpbd-bench"));
    h5::write_attr(file, "frame", static_cast<long long>(s.frame));
    h5::write_attr(file, "particles", static_cast<long long>(s.x.cols()));
    h5::write_dataset(file, "positions", std::vector<double>(s.x.data(), s.x.data() + s.x.size()));
    h5::write_dataset(file, "velocities", std::vector<double>(s.v.data(), s.v.data() + s.v.size()));
    image = h5::file_image(file);
  }
  write_file_atomically(path, image.data(), image.size());
}

SimState read_state(const std::string& path) {
  const std::string where = "--load-state: " + path;
  const h5::Guard guard;
  std::optional<H> file;
  try {
    file.emplace(h5::open_file(path));
  } catch (const Error& e) {
    throw Error(std::string("--load-state: ") + e.what());
  }
  const auto attrs = h5::read_attrs(*file, where + ": root");
  auto integer = [&](const char* name, long long lo, long long hi) {
    auto it = attrs.find(name);
    if (it == attrs.end()) throw Error(where + ": not a state file (no attribute " + name + ")");
    const auto* v = std::get_if<long long>(&it->second);
    if (!v) throw Error(where + ": attribute " + name + " is not an integer");
    if (*v < lo || *v > hi)
      throw Error(where + ": attribute " + name + " = " + std::to_string(*v) + " is out of range [" + std::to_string(lo) +
                  ", " + std::to_string(hi) + "]");
    return *v;
  };
  if (attr_text(attrs, "kind") != "state")
    throw Error(where + ": not a state file (kind is not \"state\"; write one with run --save-state)");
  SimState s;
  s.frame = static_cast<int>(integer("frame", 0, 2000000000));
  const long long n = integer("particles", 1, 1LL << 30);
  for (const char* name : {"positions", "velocities"}) {
    H d = h5::open_dataset(*file, name, where);
    const DataValue dv = h5::read_dataset(d, where + ": " + name);
    const auto* v = std::get_if<std::vector<double>>(&dv);
    if (!v) throw Error(where + ": " + name + " does not hold floats");
    if (static_cast<long long>(v->size()) != 3 * n)
      throw Error(where + ": " + name + " has " + std::to_string(v->size()) + " entries, expected 3 x " + std::to_string(n));
    (name[0] == 'p' ? s.x : s.v) = Eigen::Map<const Eigen::Matrix3Xd>(v->data(), 3, n);
  }
  return s;
}

}  // namespace xb
