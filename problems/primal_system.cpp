#include "primal_system.hpp"

#include "../core/error.hpp"
#include "problem.hpp"

#include <algorithm>
#include <numeric>

namespace xb {

ConstraintGraph constraint_graph(const Problem& prob) {
  ConstraintGraph g;
  g.particles.resize(prob.num_constraints());
  for (int j = 0; j < prob.num_constraints(); ++j) g.particles[j] = prob.constraint_particles(j);
  g.w = prob.particles.w;
  return g;
}

const std::vector<std::string>& form_choices() {
  static const std::vector<std::string> forms = {"dual", "primal", "auto"};
  return forms;
}

void check_form(const std::string& form, const std::string& where) {
  const auto& forms = form_choices();
  if (std::find(forms.begin(), forms.end(), form) != forms.end()) return;
  std::string valid;
  for (const auto& f : forms) valid += (valid.empty() ? "" : ", ") + f;
  throw Error(where + ": unknown form '" + form + "' (valid: " + valid + ")");
}

std::string resolve_form(const std::string& requested, const Eigen::VectorXd& alpha_tilde) {
  check_form(requested, "form");
  if (requested == "dual") return "dual";
  long rigid = 0;
  for (long j = 0; j < alpha_tilde.size(); ++j) rigid += !(alpha_tilde[j] > 0);
  if (rigid == 0) return "primal";
  if (requested == "auto") return "dual";
  throw Error("form=primal needs every constraint compliant (alpha~ > 0), but " + std::to_string(rigid) + " of " +
              std::to_string(alpha_tilde.size()) +
              " constraints have compliance 0: K = M + J^T alpha~^-1 J does not exist (use form=dual or form=auto)");
}

PrimalSystem::PrimalSystem(ConstraintGraph graph) : graph_(std::move(graph)) {
  build_incidence();
  build_pattern();
}

void PrimalSystem::build_incidence() {
  const int n = graph_.num_particles();
  const int m = graph_.num_constraints();
  block_of_.assign(n, -1);
  for (int p = 0; p < n; ++p)
    if (graph_.w[p] > 0) {
      block_of_[p] = static_cast<int>(free_.size());
      free_.push_back(p);
    }
  const int nb = static_cast<int>(free_.size());
  // Free particle → (constraint, slot) incidence.
  inc_start_.assign(nb + 1, 0);
  for (const auto& ps : graph_.particles)
    for (int p : ps) {
      if (p >= n) throw Error("primal system: constraint particle " + std::to_string(p) + " out of range");
      if (p >= 0 && block_of_[p] >= 0) ++inc_start_[block_of_[p] + 1];
    }
  std::partial_sum(inc_start_.begin(), inc_start_.end(), inc_start_.begin());
  inc_.resize(inc_start_[nb]);
  {
    std::vector<int> pos(inc_start_.begin(), inc_start_.end() - 1);
    for (int j = 0; j < m; ++j)
      for (int s = 0; s < 4; ++s) {
        const int p = graph_.particles[j][s];
        if (p >= 0 && block_of_[p] >= 0) inc_[pos[block_of_[p]]++] = j << 2 | s;
      }
  }
}

void PrimalSystem::build_pattern() {
  const int nb = static_cast<int>(free_.size());
  // f(q, term) for every free particle q sharing a constraint with node row p, in incidence order
  // (constraints ascending, then q's slot), term = constraint << 4 | slot_p << 2 | slot_q.
  auto for_each_pair = [&](int p, auto&& f) {
    for (int k = inc_start_[p]; k < inc_start_[p + 1]; ++k) {
      const int j = inc_[k] >> 2, sp = inc_[k] & 3;
      for (int sq = 0; sq < 4; ++sq) {
        const int q = graph_.particles[j][sq];
        if (q >= 0 && block_of_[q] >= 0) f(block_of_[q], std::int64_t(j) << 4 | sp << 2 | sq);
      }
    }
  };
  // The column nodes of node row p, each once (mark, per thread, is stamped with p, so it needs
  // no reset), p itself first: the mass block exists even without constraints.
  auto for_each_column = [&](int p, std::vector<int>& mark, auto&& f) {
    mark[p] = p;
    f(p);
    for_each_pair(p, [&](int q, std::int64_t) {
      if (mark[q] != p) {
        mark[q] = p;
        f(q);
      }
    });
  };
  block_start_.assign(nb + 1, 0);
#pragma omp parallel
  {
    std::vector<int> mark(nb, -1);
#pragma omp for schedule(static)
    for (int p = 0; p < nb; ++p) for_each_column(p, mark, [&](int) { ++block_start_[p + 1]; });
  }
  std::partial_sum(block_start_.begin(), block_start_.end(), block_start_.begin());
  const int nblk = block_start_[nb];
  block_col_.resize(nblk);
  term_start_.assign(nblk + 1, 0);
  // Per row: its sorted columns, then per block the number of terms (constraint, slot_p, slot_q).
#pragma omp parallel
  {
    std::vector<int> mark(nb, -1), pos(nb);
#pragma omp for schedule(static)
    for (int p = 0; p < nb; ++p) {
      int* cols = block_col_.data() + block_start_[p];
      int n = 0;
      for_each_column(p, mark, [&](int q) { cols[n++] = q; });
      std::sort(cols, cols + n);
      for (int k = 0; k < n; ++k) pos[cols[k]] = block_start_[p] + k;
      for_each_pair(p, [&](int q, std::int64_t) { ++term_start_[pos[q] + 1]; });
    }
  }
  std::partial_sum(term_start_.begin(), term_start_.end(), term_start_.begin());
  // The terms of each block in incidence order: blocks (p, q) and (q, p) list the same
  // constraints in the same order, so fill() makes them exact transposes.
  terms_.resize(term_start_[nblk]);
  std::vector<int> cursor(term_start_.begin(), term_start_.end() - 1);  // per block: its next term
#pragma omp parallel
  {
    std::vector<int> pos(nb);
#pragma omp for schedule(static)
    for (int p = 0; p < nb; ++p) {
      for (int k = block_start_[p]; k < block_start_[p + 1]; ++k) pos[block_col_[k]] = k;
      for_each_pair(p, [&](int q, std::int64_t term) { terms_[cursor[pos[q]]++] = term; });
    }
  }
  build_csr();
}

void PrimalSystem::build_csr() {
  const int nb = static_cast<int>(free_.size());
  const int nblk = block_start_[nb];
  // Scalar CSR: node row p has 3 rows of 3·(its blocks) entries each, columns 3q, 3q+1, 3q+2.
  K_.resize(3 * nb, 3 * nb);
  K_.resizeNonZeros(9L * nblk);
  int* outer = K_.outerIndexPtr();
  int* cols = K_.innerIndexPtr();
#pragma omp parallel for schedule(static)
  for (int p = 0; p < nb; ++p) {
    const int nbp = block_start_[p + 1] - block_start_[p];
    for (int r = 0; r < 3; ++r) {
      const int start = 9 * block_start_[p] + 3 * nbp * r;
      outer[3 * p + r] = start;
      for (int k = 0; k < nbp; ++k)
        for (int c = 0; c < 3; ++c) cols[start + 3 * k + c] = 3 * block_col_[block_start_[p] + k] + c;
    }
  }
  outer[3 * nb] = 9 * nblk;
  std::fill(K_.valuePtr(), K_.valuePtr() + 9L * nblk, 0.0);
}

void PrimalSystem::set_inverse_alpha(const Eigen::VectorXd& alpha_tilde) {
  // One division per constraint, not nine per term: a term is (g_p g_qᵀ)·(1/α̃), in that order
  // so that the blocks (p, q) and (q, p) stay exact transposes.
  inv_alpha_.resize(alpha_tilde.size());
  for (long j = 0; j < alpha_tilde.size(); ++j) {
    if (!(alpha_tilde[j] > 0))
      throw Error("primal system: constraint " + std::to_string(j) + " has alpha~ = " + std::to_string(alpha_tilde[j]) +
                  " (the primal form needs every alpha~ > 0)");
    inv_alpha_[j] = 1.0 / alpha_tilde[j];
  }
}

void PrimalSystem::fill(const Gradients& grad, const Eigen::VectorXd& alpha_tilde) {
  set_inverse_alpha(alpha_tilde);
  fill_values<true, false>(&grad, nullptr, nullptr);
}

void PrimalSystem::fill_with_diagonal(const Gradients& grad, const Eigen::VectorXd& alpha_tilde, const Eigen::Matrix3Xd& kd) {
  if (kd.cols() != graph_.num_particles()) throw Error("primal system: kd has " + std::to_string(kd.cols()) + " columns, not one per particle");
  set_inverse_alpha(alpha_tilde);
  fill_values<true, false>(&grad, &kd, nullptr);
}

void PrimalSystem::fill_with_blocks(const Gradients& grad, const Eigen::VectorXd& alpha_tilde, const ElementMatrices& G) {
  if (G.size() != graph_.num_constraints()) throw Error("primal system: not one block per constraint");
  set_inverse_alpha(alpha_tilde);
  fill_values<true, true>(&grad, nullptr, &G);
}

void PrimalSystem::fill_energy_hessian(const ElementMatrices& H) {
  if (H.size() != graph_.num_constraints()) throw Error("primal system: not one block per constraint");
  fill_values<false, true>(nullptr, nullptr, &H);
}

void PrimalSystem::fix_dofs(const std::vector<int>& dofs) {
  const int* outer = K_.outerIndexPtr();
  const int* cols = K_.innerIndexPtr();
  double* val = K_.valuePtr();
  for (int d : dofs) {
    for (int k = outer[d]; k < outer[d + 1]; ++k) {
      const int c = cols[k];
      if (c == d) continue;
      val[k] = 0;
      // The symmetric entry (c, d): the pattern is symmetric and each row's columns sorted.
      const int* hit = std::lower_bound(cols + outer[c], cols + outer[c + 1], d);
      if (hit != cols + outer[c + 1] && *hit == d) val[hit - cols] = 0;
    }
  }
}

template <bool kGaussNewton, bool kBlocks>
void PrimalSystem::fill_values(const Gradients* grad, const Eigen::Matrix3Xd* kd, const ElementMatrices* blocks) {
  const int nb = static_cast<int>(free_.size());
  double* val = K_.valuePtr();
  constexpr int kAhead = 2;
#pragma omp parallel for schedule(static)
  for (int p = 0; p < nb; ++p) {
    // The gradients (and element columns) of a later node row's constraints, whose loads would
    // otherwise stall.
    if (p + kAhead < nb)
      for (int k = inc_start_[p + kAhead]; k < inc_start_[p + kAhead + 1]; ++k) {
        if constexpr (kGaussNewton) {
          const char* g = reinterpret_cast<const char*>((*grad)[inc_[k] >> 2].data());
          __builtin_prefetch(g);
          __builtin_prefetch(g + 64);
        }
        if constexpr (kBlocks) {
          const int j = inc_[k] >> 2, n = 3 * blocks->slots(j);  // slot's 3 columns: 3n doubles
          const char* e = reinterpret_cast<const char*>(blocks->data(j) + 3 * n * (inc_[k] & 3));
          for (int c = 0; c < 24 * n; c += 64) __builtin_prefetch(e + c);
        }
      }
    const int nbp = block_start_[p + 1] - block_start_[p];
    for (int k = 0; k < nbp; ++k) {
      const int blk = block_start_[p] + k;
      Eigen::Matrix3d B = Eigen::Matrix3d::Zero();
      for (int t = term_start_[blk]; t < term_start_[blk + 1]; ++t) {
        const std::int64_t term = terms_[t];
        const int j = static_cast<int>(term >> 4), sp = (term >> 2) & 3, sq = term & 3;
        if constexpr (kGaussNewton) B.noalias() += ((*grad)[j][sp] * (*grad)[j][sq].transpose()) * inv_alpha_[j];
        // Block (sp, sq) read as the transpose of (sq, sp): a node row then reads its slot's
        // 3 contiguous columns of each element (the blocks are exactly symmetric).
        if constexpr (kBlocks) B += blocks->block(j, sq, sp).transpose();
      }
      if (block_col_[blk] == p) {
        B.diagonal().array() += 1.0 / graph_.w[free_[p]];
        if (kd) B.diagonal() += kd->col(free_[p]);
      }
      for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c) val[9 * block_start_[p] + 3 * nbp * r + 3 * k + c] = B(r, c);
    }
  }
}

void PrimalSystem::apply_J(const Gradients& grad, const Vector& v, Vector& out) const { apply_J(grad, v, 1.0, false, out); }

void PrimalSystem::apply_J(const Gradients& grad, const Vector& v, double sign, bool times_minv, Vector& out) const {
  const int m = graph_.num_constraints();
  out.resize(m);
#pragma omp parallel for schedule(static)
  for (int j = 0; j < m; ++j) {
    double s = 0;
    for (int a = 0; a < 4; ++a) {
      const int p = graph_.particles[j][a];
      if (p < 0 || block_of_[p] < 0) continue;
      const double d = grad[j][a].dot(v.segment<3>(3 * block_of_[p]));
      s += times_minv ? graph_.w[p] * d : d;
    }
    out[j] = sign * s;
  }
}

void PrimalSystem::apply_JT(const Gradients& grad, const Eigen::VectorXd& y, Vector& out) const {
  const int nb = static_cast<int>(free_.size());
  out.resize(3 * nb);
#pragma omp parallel for schedule(static)
  for (int p = 0; p < nb; ++p) {
    Eigen::Vector3d acc = Eigen::Vector3d::Zero();
    for (int k = inc_start_[p]; k < inc_start_[p + 1]; ++k) acc += grad[inc_[k] >> 2][inc_[k] & 3] * y[inc_[k] >> 2];
    out.segment<3>(3 * p) = acc;
  }
}

void PrimalSystem::rhs(const Gradients& grad, const Eigen::VectorXd& alpha_tilde, const Vector& b, Vector& f) const {
  apply_JT(grad, b.cwiseQuotient(alpha_tilde), f);
}

void PrimalSystem::recover(const Gradients& grad, const Eigen::VectorXd& alpha_tilde, const Vector& b,
                           const Vector& dx, Vector& dlambda) const {
  apply_J(grad, dx, dlambda);
  dlambda = (b - dlambda).cwiseQuotient(alpha_tilde);
}

void PrimalSystem::dual_residual(const Gradients& grad, const Vector& r_K, Vector& out) const {
  apply_J(grad, r_K, -1.0, true, out);  // −J M⁻¹ r_K in one pass, no temporary
}

void PrimalSystem::dual_residual(const Gradients& grad, const Vector& r_K, const Eigen::Matrix3Xd& w_dof, Vector& out) const {
  const int m = graph_.num_constraints();
  out.resize(m);
#pragma omp parallel for schedule(static)
  for (int j = 0; j < m; ++j) {
    double s = 0;
    for (int a = 0; a < 4; ++a) {
      const int p = graph_.particles[j][a];
      if (p < 0 || block_of_[p] < 0) continue;
      s += grad[j][a].dot(w_dof.col(p).cwiseProduct(r_K.segment<3>(3 * block_of_[p])));
    }
    out[j] = -s;
  }
}

template <class Y>
void PrimalSystem::inertia_minus_JT(const Gradients& grad, Y&& ys, const Eigen::Matrix3Xd& x,
                                    const Eigen::Matrix3Xd& x_pred, Vector& out) const {
  const int nb = static_cast<int>(free_.size());
  out.resize(3 * nb);
#pragma omp parallel for schedule(static)
  for (int b = 0; b < nb; ++b) {
    const int p = free_[b];
    Eigen::Vector3d acc = (x.col(p) - x_pred.col(p)) / graph_.w[p];
    for (int k = inc_start_[b]; k < inc_start_[b + 1]; ++k) acc -= grad[inc_[k] >> 2][inc_[k] & 3] * ys(inc_[k] >> 2);
    out.segment<3>(3 * b) = acc;
  }
}

void PrimalSystem::primal_residual(const Gradients& grad, const Eigen::VectorXd& lambda, const Eigen::Matrix3Xd& x,
                                   const Eigen::Matrix3Xd& x_pred, Vector& g) const {
  inertia_minus_JT(grad, [&](int j) { return lambda[j]; }, x, x_pred, g);
}

void PrimalSystem::energy_gradient(const Gradients& grad, const Eigen::VectorXd& C, const Eigen::VectorXd& alpha_tilde,
                                   const Eigen::Matrix3Xd& x, const Eigen::Matrix3Xd& x_pred, Vector& out) const {
  inertia_minus_JT(grad, [&](int j) { return -C[j] / alpha_tilde[j]; }, x, x_pred, out);
}

Eigen::MatrixXd PrimalSystem::rigid_modes(const Eigen::Matrix3Xd& x) const {
  const int nb = static_cast<int>(free_.size());
  Eigen::Vector3d c = Eigen::Vector3d::Zero();
  for (int p : free_) c += x.col(p);
  if (nb > 0) c /= nb;
  Eigen::MatrixXd B = Eigen::MatrixXd::Zero(3 * nb, 6);
  for (int i = 0; i < nb; ++i) {
    const Eigen::Vector3d d = x.col(free_[i]) - c;
    for (int k = 0; k < 3; ++k) {
      B(3 * i + k, k) = 1;
      B.block<3, 1>(3 * i, 3 + k) = Eigen::Vector3d::Unit(k).cross(d);
    }
  }
  return B;
}

}  // namespace xb
