#include "reference_file.hpp"

#include "atomic_file.hpp"
#include "file_lock.hpp"
#include "h5io.hpp"
#include "system_io.hpp"

#include "../../core/error.hpp"

#include <filesystem>

namespace fs = std::filesystem;

namespace xb {

using h5::H;

namespace {

const char* const kind = "reference";

std::string group_name(long long frame, long long substep) {
  return "f" + std::to_string(frame) + "_s" + std::to_string(substep);
}

std::optional<H> open_reference_file(const std::string& path) {
  if (!fs::exists(path)) return std::nullopt;
  return h5::open_file(path);
}

ReferenceFileHeader header_of(hid_t file, const std::string& path) {
  const auto attrs = h5::read_attrs(file, path + ": root");
  if (attr_text(attrs, "kind") != kind)
    throw Error(path + ": not a reference file (kind is not \"reference\"; run --reference-file writes one)");
  ReferenceFileHeader h;
  h.problem_hash = attr_text(attrs, "problem_hash");
  h.problem = attr_text(attrs, "problem");
  h.method = attr_text(attrs, "reference_method");
  auto it = attrs.find("particles");
  const auto* n = it == attrs.end() ? nullptr : std::get_if<long long>(&it->second);
  if (h.problem_hash.empty() || !n || *n < 1)
    throw Error(path + ": a reference file without problem_hash or particles (not written by xpbd-bench?)");
  h.particles = *n;
  return h;
}

StoredReference entry_of(hid_t file, const std::string& path, const std::string& name, long long particles) {
  const std::string where = path + ": " + name;
  H g = h5::open_group(file, name, path);
  StoredReference r;
  r.fields = h5::read_attrs(g, where);
  auto integer = [&](const char* key) {
    auto it = r.fields.find(key);
    const auto* v = it == r.fields.end() ? nullptr : std::get_if<long long>(&it->second);
    if (!v) throw Error(where + ": no integer attribute " + key);
    const long long out = *v;
    r.fields.erase(it);
    return out;
  };
  r.frame = integer("frame");
  r.substep = integer("substep");
  r.state_hash = attr_text(r.fields, "state_hash");
  r.fields.erase("state_hash");
  H d = h5::open_dataset(g, "positions", where);
  const DataValue dv = h5::read_dataset(d, where + "/positions");
  const auto* x = std::get_if<std::vector<double>>(&dv);
  if (!x || static_cast<long long>(x->size()) != 3 * particles)
    throw Error(where + "/positions: expected 3 x " + std::to_string(particles) + " floats");
  r.x = Eigen::Map<const Eigen::Matrix3Xd>(x->data(), 3, particles);
  return r;
}

void write_entry(hid_t file, const StoredReference& r) {
  H lcpl = h5::link_create_plist();
  H g(H5Gcreate2(file, group_name(r.frame, r.substep).c_str(), lcpl, H5P_DEFAULT, H5P_DEFAULT), H5Gclose);
  h5::check_id(g, "create group " + group_name(r.frame, r.substep));
  for (const auto& [k, v] : r.fields) h5::write_attr(g, k, v);
  h5::write_attr(g, "frame", r.frame);
  h5::write_attr(g, "substep", r.substep);
  h5::write_attr(g, "state_hash", r.state_hash);
  h5::write_dataset(g, "positions", std::vector<double>(r.x.data(), r.x.data() + r.x.size()));
}

}  // namespace

std::optional<ReferenceFileHeader> read_reference_header(const std::string& path) {
  const h5::Guard guard;
  std::optional<H> file = open_reference_file(path);
  if (!file) return std::nullopt;
  return header_of(*file, path);
}

std::optional<StoredReference> read_reference(const std::string& path, long long frame, long long substep) {
  const h5::Guard guard;
  std::optional<H> file = open_reference_file(path);
  if (!file) return std::nullopt;
  const ReferenceFileHeader h = header_of(*file, path);
  const std::string name = group_name(frame, substep);
  if (h5::link_kind(*file, name) == h5::Kind::missing) return std::nullopt;
  return entry_of(*file, path, name, h.particles);
}

bool add_reference(const std::string& path, const ReferenceFileHeader& header, const StoredReference& ref) {
  const FileLock lock(path + ".lock", FileLock::Kind::exclusive, path);
  std::vector<StoredReference> entries;
  std::vector<char> image;
  {
    const h5::Guard guard;
    if (std::optional<H> old = open_reference_file(path)) {
      const ReferenceFileHeader h = header_of(*old, path);
      if (h.problem_hash != header.problem_hash)
        throw Error(path + ": holds references of another problem (problem_hash " + h.problem_hash + ", this run's " +
                    header.problem_hash + ")");
      for (const std::string& name : h5::link_names(*old, path)) {
        if (name == group_name(ref.frame, ref.substep)) return false;
        entries.push_back(entry_of(*old, path, name, h.particles));
      }
    }
    entries.push_back(ref);
    H file = h5::create_memory_file();
    h5::write_attr(file, "kind", std::string(kind));
    h5::write_attr(file, "generator", std::string("xpbd-bench"));
    h5::write_attr(file, "problem_hash", header.problem_hash);
    h5::write_attr(file, "problem", header.problem);
    h5::write_attr(file, "reference_method", header.method);
    h5::write_attr(file, "particles", header.particles);
    for (const StoredReference& r : entries) write_entry(file, r);
    image = h5::file_image(file);
  }
  write_file_atomically(path, image.data(), image.size());
  return true;
}

}  // namespace xb
