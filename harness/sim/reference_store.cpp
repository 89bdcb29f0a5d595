#include "reference_store.hpp"

#include "../../core/error.hpp"

#include <algorithm>
#include <cstdio>
#include <sstream>
#include <type_traits>
#include <variant>

namespace xb {

std::string hash_hex(const void* data, std::size_t n) {
  unsigned long long h = 14695981039346656037ULL;
  const auto* b = static_cast<const unsigned char*>(data);
  for (std::size_t i = 0; i < n; ++i) h = (h ^ b[i]) * 1099511628211ULL;
  char text[17];
  std::snprintf(text, sizeof text, "%016llx", h);
  return text;
}

std::string reference_problem(const Params& p, const Problem& prob, const Eigen::VectorXd& alpha_tilde) {
  std::ostringstream os;
  for (const auto& f : scene_settings())
    if (f.key != "frames") os << f.key << " = " << param_to_string(p, *find_param(f.key)) << "\n";
  os << "reference.method = " << resolve_reference_method(p.reference_method, alpha_tilde) << "\n";
  os << "reference.linear = " << p.reference_linear << "\n";
  char h[32];
  std::snprintf(h, sizeof h, "%.17g", p.dt / p.substeps);
  os << "h = " << h << "\n";
  os << "particles = " << prob.particles.size() << "\n";
  os << "constraints = " << prob.num_constraints() << "\n";
  const Eigen::VectorXd& w = prob.particles.w;
  os << "inverse_masses = " << hash_hex(w.data(), sizeof(double) * w.size()) << "\n";
  os << "alpha_tilde = " << hash_hex(alpha_tilde.data(), sizeof(double) * alpha_tilde.size()) << "\n";
  return os.str();
}

namespace {

// The lines of `a` not in `b`, and of `b` not in `a`: what differs between two problems.
std::string difference(const std::string& stored, const std::string& here) {
  auto lines = [](const std::string& t) {
    std::vector<std::string> out;
    std::istringstream is(t);
    for (std::string l; std::getline(is, l);) out.push_back(l);
    return out;
  };
  const auto a = lines(stored), b = lines(here);
  std::string out;
  for (const auto& l : a)
    if (std::find(b.begin(), b.end(), l) == b.end()) out += (out.empty() ? "" : "; ") + ("file: " + l);
  for (const auto& l : b)
    if (std::find(a.begin(), a.end(), l) == a.end()) out += (out.empty() ? "" : "; ") + ("this run: " + l);
  return out;
}

std::string state_hash(const Eigen::Matrix3Xd& x) { return hash_hex(x.data(), sizeof(double) * x.size()); }

}  // namespace

ReferenceStore::ReferenceStore(std::string path, const Params& p, const Problem& prob, const Eigen::VectorXd& alpha_tilde)
    : path_(std::move(path)) {
  header_.problem = reference_problem(p, prob, alpha_tilde);
  header_.problem_hash = hash_hex(header_.problem.data(), header_.problem.size());
  header_.method = reference_description(p, alpha_tilde);
  header_.particles = prob.particles.size();
  const std::optional<ReferenceFileHeader> stored = read_reference_header(path_);
  if (!stored) return;
  if (stored->problem_hash != header_.problem_hash)
    throw Error("--reference-file " + path_ + " holds the references of another problem (" +
                difference(stored->problem, header_.problem) + "): give another file, or delete it to recompute");
  header_.method = stored->method;
}

std::optional<ReferenceSolution> ReferenceStore::find(int frame, int substep, const Eigen::Matrix3Xd& x_pred) const {
  const std::optional<StoredReference> s = read_reference(path_, frame, substep);
  if (!s || s->state_hash != state_hash(x_pred)) return std::nullopt;
  ReferenceSolution r;
  r.x = s->x;
  const std::string where = path_ + ": the reference of frame " + std::to_string(frame) + ", substep " + std::to_string(substep);
  for (const ReferenceField& f : reference_fields) {
    auto it = s->fields.find(f.name);
    if (it == s->fields.end())
      throw Error(where + " has no field " + f.name + " (an older file): delete it to recompute");
    std::visit(
        [&](auto member) {
          using T = std::decay_t<decltype(r.*member)>;
          const AttrValue& v = it->second;
          if constexpr (std::is_same_v<T, std::string>) {
            if (auto* t = std::get_if<std::string>(&v)) return void(r.*member = *t);
          } else if constexpr (std::is_same_v<T, StopReason>) {
            if (auto* t = std::get_if<std::string>(&v)) return void(r.*member = stop_reason_from_name(*t));
          } else if constexpr (std::is_same_v<T, double>) {
            if (auto* d = std::get_if<double>(&v)) return void(r.*member = *d);
          } else {
            if (auto* i = std::get_if<long long>(&v)) return void(r.*member = static_cast<T>(*i));
          }
          throw Error(where + ": field " + f.name + " has the wrong type");
        },
        f.member);
  }
  return r;
}

bool ReferenceStore::store(int frame, int substep, const Eigen::Matrix3Xd& x_pred, const ReferenceSolution& r,
                           double seconds) const {
  StoredReference s;
  s.frame = frame;
  s.substep = substep;
  s.state_hash = state_hash(x_pred);
  s.x = r.x;
  for (const ReferenceField& f : reference_fields)
    std::visit(
        [&](auto member) {
          using T = std::decay_t<decltype(r.*member)>;
          if constexpr (std::is_same_v<T, std::string> || std::is_same_v<T, double>) {
            s.fields[f.name] = r.*member;
          } else if constexpr (std::is_same_v<T, StopReason>) {
            s.fields[f.name] = stop_reason_name(r.*member);
          } else {
            s.fields[f.name] = static_cast<long long>(r.*member);
          }
        },
        f.member);
  s.fields["compute_time"] = seconds;
  return add_reference(path_, header_, s);
}

}  // namespace xb
