#include "vbd_settings.hpp"

#include "../../core/error.hpp"

namespace xb {

namespace {
// The keys of each method: vbd reads vbd.*, avbd reads avbd.* and vbd.init.
bool reads(const std::string& method, const std::string& key) {
  if (method == "vbd") return key.rfind("vbd.", 0) == 0;
  if (method == "avbd") return key.rfind("avbd.", 0) == 0 || key == "vbd.init";
  return false;
}
}  // namespace

const SettingTable<BlockDescentSettings>& block_descent_settings() {
  using S = BlockDescentSettings;
  static const SettingTable<S> table = [] {
    SettingTable<S> t;
    const SettingTable<VbdSettings> vbd = {
        setting("vbd.init", "vbd, avbd: start of each substep (VBD 3.7): previous (x_t) | inertia (x_t + h v_t) | inertia_acceleration (x~ = x_t + h v_t + h^2 g) | adaptive (x_t + h v_t + h^2 a~ g, a~ = the last step's acceleration along g over |g|^2, in [0, 1])", &VbdSettings::init, {"previous", "inertia", "inertia_acceleration", "adaptive"}),
        setting("vbd.acceleration", "vbd: after each sweep (VBD 3.8): none | chebyshev (x <- omega_n (x - x_{n-2}) + x_{n-2}, omega from vbd.rho)", &VbdSettings::acceleration, {"none", "chebyshev"}),
        setting("vbd.rho", "vbd: chebyshev's spectral radius estimate rho", &VbdSettings::rho, 0, 0.9999),
        setting("vbd.projection", "vbd: each element Hessian of C^2/(2 alpha~) made PSD before its vertex block is taken: clamp | abs | none (a vertex whose 3x3 is then singular is skipped)", &VbdSettings::projection, {"clamp", "abs", "none"}),
        setting("vbd.damping", "vbd: VBD's damping k_d, s (force -(k_d/h) H_i (x_i - x_i^t) per vertex; 0 = none)", &VbdSettings::damping, 0, 1e300),
        setting("vbd.contact_stiffness", "vbd: ground contact by penalty, k_c = this * m_p / h^2 per particle (N/m)", &VbdSettings::contact_stiffness, 1e-300, 1e300),
    };
    const SettingTable<AvbdSettings> avbd = {
        setting("avbd.alpha", "avbd: rigid constraints correct (1 - alpha) of the error a step starts with; lambda warm start alpha*gamma", &AvbdSettings::alpha, 0, 1),
        setting("avbd.gamma", "avbd: warm start of each step: lambda <- alpha gamma lambda, kappa <- max(gamma kappa, avbd.stiffness_start)", &AvbdSettings::gamma, 0, 1),
        setting("avbd.beta", "avbd: stiffness ramp after each sweep, kappa <- kappa + beta |C|/c (c: a distance's rest length, 1 for a tet, the mean edge for contact)", &AvbdSettings::beta, 0, 1e300),
        setting("avbd.stiffness_start", "avbd: kappa of a new constraint and the warm start's floor; k = kappa / sum_a w_a |grad_a C|^2 (mass units)", &AvbdSettings::stiffness_start, 1e-300, 1e300),
        setting("avbd.stiffness_max", "avbd: the ramp's cap on kappa", &AvbdSettings::stiffness_max, 1e-300, 1e300),
        setting("avbd.hessian", "avbd: each vertex block's Hessian: projected (the geometric term f hess C made PSD, as vbd) | diagonal (AVBD's: |f| diag(column norms of hess C))", &AvbdSettings::hessian, {"projected", "diagonal"}),
        setting("avbd.compliant", "avbd: compliant constraints (alpha~ > 0): augmented (a multiplier too, exact for any k) | penalty (AVBD's: no multiplier, k ramped up to 1/alpha~)", &AvbdSettings::compliant, {"augmented", "penalty"}),
    };
    append_part(t, vbd, [](S& s) -> VbdSettings& { return s.vbd; });
    append_part(t, avbd, [](S& s) -> AvbdSettings& { return s.avbd; });
    return t;
  }();
  return table;
}

bool is_block_descent(const std::string& method) { return method == "vbd" || method == "avbd"; }

void check_block_descent_keys(const BlockDescentSettings& s, const std::string& method) {
  const BlockDescentSettings defaults;
  for (const auto& f : block_descent_settings()) {
    if (reads(method, f.key) || setting_text(f, s) == setting_text(f, defaults)) continue;
    const std::string who = f.key.rfind("avbd.", 0) == 0 ? "avbd" : f.key == "vbd.init" ? "vbd and avbd" : "vbd";
    throw Error("parameter '" + f.key + "' = '" + setting_text(f, s) + "' applies to --solver " + who + ", not '" + method +
                "'");
  }
}

}  // namespace xb
