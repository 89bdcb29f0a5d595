// The settings of the block-descent methods on the incremental potential (docs/vbd.md): vbd.* for
// Vertex Block Descent (Chen et al. 2024; `--solver vbd`), avbd.* for its augmented form (Giles et
// al. 2025; `--solver avbd`), which also reads vbd.init.
#pragma once

#include "../../core/settings.hpp"

#include <string>

namespace xb {

struct VbdSettings {
  // §3.7's start of each substep: previous (x_t) | inertia (x_t + h v_t) | inertia_acceleration (x_t + h v_t +
  // h² a_ext = x̃, where the other methods start) | adaptive (x_t + h v_t + h² ã a_ext, ã = the previous step's
  // acceleration along a_ext over |a_ext|², clamped to [0, 1]).
  std::string init = "adaptive";
  // §3.8: none | chebyshev (x ← ω_n(x̄ − x_{n−2}) + x_{n−2} after each sweep, ω from the estimate rho).
  std::string acceleration = "none";
  double rho = 0.95;
  // How each element's Hessian of ½C²/α̃ is made PSD before its vertex block is taken: clamp | abs | none.
  std::string projection = "clamp";
  double damping = 0;             // k_d, s: VBD's damping (0: none)
  double contact_stiffness = 1e3;  // κ_c: the ground's penalty k_c = κ_c m_p/h² per particle
};

struct AvbdSettings {
  double alpha = 0.95;  // hard constraints correct (1 − α) of the error they start a step with; λ warm start α·γ
  double gamma = 0.99;  // warm start of the next step: λ ← αγλ, k ← max(γk, k_start)
  double beta = 1e3;    // stiffness ramp after each sweep: κ ← κ + β|C|/c (c: a distance's rest length, 1 for a tet)
  double stiffness_start = 100;  // κ at the first step (and the warm start's floor); k = κ·u, u = 1/Σ_a w_a|∇_aC|²
  double stiffness_max = 1e8;    // the ramp's cap on κ
  // Compliant constraints (α̃ > 0): augmented (a multiplier for them too: the augmented Lagrangian of C = s with
  // ½s²/α̃ eliminated, exact for any k) | penalty (AVBD's: no multiplier, k ramped up to 1/α̃).
  std::string compliant = "augmented";
  // The Hessian of each vertex's block: projected (each constraint's geometric term made PSD, as VBD's)
  // | diagonal (AVBD's: |f| times the diagonal of the column norms of ∇²C).
  std::string hessian = "projected";
};

struct BlockDescentSettings {
  VbdSettings vbd;
  AvbdSettings avbd;
};

const SettingTable<BlockDescentSettings>& block_descent_settings();
// The method names of the block-descent family.
bool is_block_descent(const std::string& method);
// Throws xb::Error naming the first key set away from its default that `method` does not read:
// vbd.* other than vbd.init under avbd, avbd.* under vbd, any of them under another method.
void check_block_descent_keys(const BlockDescentSettings& s, const std::string& method);

}  // namespace xb
