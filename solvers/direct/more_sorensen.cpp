#include "more_sorensen.hpp"

#include "../kernels.hpp"
#include "../krylov/steihaug.hpp"

#include "../../core/error.hpp"

#include <algorithm>
#include <cmath>

namespace xb {

MoreSorensen::MoreSorensen(std::unique_ptr<LinearSolver> direct, double accuracy, int max_factorisations)
    : direct_(std::move(direct)), kappa_(accuracy), max_factorisations_(max_factorisations) {
  if (!direct_) throw Error("More-Sorensen: no direct solver");
}

bool MoreSorensen::factorise(const SparseMatrix& K, const Vector& D, double sigma) {
  const bool same = analysed_ && S_.rows() == K.rows() && S_.nonZeros() == K.nonZeros();
  if (!same) {
    S_ = K;
    diag_.assign(K.rows(), -1);
    for (int i = 0; i < K.rows(); ++i)
      for (int k = S_.outerIndexPtr()[i]; k < S_.outerIndexPtr()[i + 1]; ++k)
        if (S_.innerIndexPtr()[k] == i) diag_[i] = k;
    for (int i = 0; i < K.rows(); ++i)
      if (diag_[i] < 0) throw Error("More-Sorensen: K has no diagonal entry in row " + std::to_string(i));
  } else {
    std::copy(K.valuePtr(), K.valuePtr() + K.nonZeros(), S_.valuePtr());
  }
  for (int i = 0; i < K.rows(); ++i) S_.valuePtr()[diag_[i]] += sigma * D[i];
  direct_->setup(S_, same ? SetupKind::Values : SetupKind::Structure, SetupContext{});
  analysed_ = true;
  return direct_->preconditioner() != nullptr;  // a factor exists: S is positive definite
}

namespace {
double d_dot(const Vector& D, const Vector& a, const Vector& b) { return (a.array() * D.array() * b.array()).sum(); }

// The safeguarded next shift inside (lo, hi): where Newton's step left the bracket.
double inside(double lo, double hi) { return std::max(std::sqrt(lo * hi), lo + 0.01 * (hi - lo)); }
}  // namespace

MoreSorensenResult MoreSorensen::solve(const SparseMatrix& K, const Vector& D, const Vector& g, double radius,
                                       const Vector* u) {
  if (!(radius > 0)) throw Error("More-Sorensen: the trust-region radius must be > 0");
  const long n = g.size();
  if (K.rows() != n || D.size() != n) throw Error("More-Sorensen: K, D and g differ in size");
  // The bracket, in the scaled variables y = D^½p (Ĥ = D^-½KD^-½, ĝ = D^-½g).
  double gD = 0, hinf = 0, dmin = INFINITY;
  for (long i = 0; i < n; ++i) {
    gD += g[i] * g[i] / D[i];
    double row = 0;
    for (SparseMatrix::InnerIterator it(K, i); it; ++it) {
      row += std::abs(it.value()) / std::sqrt(D[i] * D[it.col()]);
      if (it.col() == i) dmin = std::min(dmin, it.value() / D[i]);
    }
    hinf = std::max(hinf, row);
  }
  gD = std::sqrt(gD);
  double lo = std::max({0.0, -dmin, gD / radius - hinf}), hi = std::max(0.0, gD / radius + hinf);
  Vector Ku;
  double uKu = 0, uDu = 0;
  const bool has_u = u && u->size() == n;
  if (has_u) {
    uKu = spmv_dot(K, *u, Ku);
    uDu = d_dot(D, *u, *u);
    if (uDu > 0 && uKu < 0) lo = std::max(lo, -uKu / uDu);
  }
  MoreSorensenResult out;
  Vector p, Dp, w, best;
  double best_sigma = 0, best_norm = 0;
  bool have_best = false;
  double sigma = lo;
  for (; out.factorisations < max_factorisations_; ) {
    ++out.factorisations;
    if (!factorise(K, D, sigma)) {
      ++out.failed;
      lo = std::max(lo, sigma);
      sigma = hi > lo ? inside(lo, hi) : 2 * std::max(lo, 1e-300);
      if (hi <= lo) hi = 2 * sigma;
      continue;
    }
    direct_->solve(-g, p);
    const double np = std::sqrt(d_dot(D, p, p));
    if (np <= (1 + kappa_) * radius) {  // a feasible step: the best so far (larger σ: smaller norm)
      best = p, best_sigma = sigma, best_norm = np, have_best = true;
    }
    if ((sigma == 0 && np <= radius) || std::abs(np - radius) <= kappa_ * radius) break;
    if (np < radius) {
      hi = sigma;
      if (has_u && uDu > 0) {  // the hard case: along u to the boundary, if its curvature is small
        const double pDu = d_dot(D, p, *u);
        const double sign = pDu >= 0 ? 1 : -1;  // the linear term −στ uᵀDp ≤ 0
        const double tau = sign * step_to_boundary(np * np, sign * pDu, uDu, radius);
        Vector Sp;
        const double pSp = spmv_dot(K, p, Sp) + sigma * np * np;
        const double uSu = uKu + sigma * uDu;
        if (tau * tau * uSu <= kappa_ * (2 - kappa_) * std::max(pSp + sigma * radius * radius, 0.0)) {
          best = p + tau * *u, best_sigma = sigma, best_norm = radius, have_best = true;
          out.hard_case = true;
          break;
        }
      }
    } else {
      lo = sigma;
    }
    Dp = D.cwiseProduct(p);
    direct_->solve(Dp, w);
    const double qq = dot(Dp, w);
    double next = sigma + (np * np / qq) * (np - radius) / radius;
    if (!(next > lo && next < hi)) next = inside(lo, hi);
    if (hi - lo <= 1e-12 * hi) break;
    sigma = next;
  }
  if (!have_best && p.size() == n && out.factorisations > out.failed) {  // only steps too long: cut to the boundary
    const double np = std::sqrt(d_dot(D, p, p));
    best = p * (radius / np), best_sigma = sigma, best_norm = radius, have_best = true;
  }
  if (!have_best) {
    out.message = "no shift sigma in " + std::to_string(out.factorisations) +
                  " factorisations made K + sigma D positive definite (last sigma " + std::to_string(sigma) + ")";
    out.p = Vector::Zero(n);
    return out;
  }
  out.ok = true;
  out.p = std::move(best);
  out.sigma = best_sigma;
  out.norm = best_norm;
  out.boundary = best_sigma > 0 || out.hard_case;
  out.model = dot(g, out.p) + 0.5 * spmv_dot(K, out.p, out.Kp);
  return out;
}

}  // namespace xb
