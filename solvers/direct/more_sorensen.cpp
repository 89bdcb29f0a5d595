#include "more_sorensen.hpp"

#include "../kernels.hpp"
#include "../krylov/steihaug.hpp"

#include "../../core/error.hpp"

#include <algorithm>
#include <cmath>

namespace xb {

double RegionNorm::dot(const Vector& a, const Vector& b) const {
  if (diagonal) return (a.array() * diagonal->array() * b.array()).sum();
  Vector Db;
  spmv(*matrix, b, Db);
  return xb::dot(a, Db);
}

void RegionNorm::apply(const Vector& a, Vector& out) const {
  if (diagonal)
    out = diagonal->cwiseProduct(a);
  else
    spmv(*matrix, a, out);
}

MoreSorensen::MoreSorensen(std::unique_ptr<LinearSolver> direct, double accuracy, int max_factorisations)
    : direct_(std::move(direct)), kappa_(accuracy), max_factorisations_(max_factorisations) {
  if (!direct_) throw Error("More-Sorensen: no direct solver");
}

bool MoreSorensen::factorise(const SparseMatrix& K, const RegionNorm& D, double sigma) {
  const bool same = analysed_ && S_.rows() == K.rows() && S_.nonZeros() == K.nonZeros();
  if (!same) {
    S_ = K;
    diag_.assign(K.rows(), -1);
    for (int i = 0; i < K.rows(); ++i)
      for (int k = S_.outerIndexPtr()[i]; k < S_.outerIndexPtr()[i + 1]; ++k)
        if (S_.innerIndexPtr()[k] == i) diag_[i] = k;
    for (int i = 0; i < K.rows(); ++i)
      if (diag_[i] < 0) throw Error("More-Sorensen: K has no diagonal entry in row " + std::to_string(i));
  }
  if (D.matrix) {
    if (D.matrix->nonZeros() != K.nonZeros()) throw Error("More-Sorensen: the norm's matrix has another pattern than K");
    const double* k = K.valuePtr();
    const double* d = D.matrix->valuePtr();
    double* s = S_.valuePtr();
    for (long i = 0; i < K.nonZeros(); ++i) s[i] = k[i] + sigma * d[i];
  } else {
    std::copy(K.valuePtr(), K.valuePtr() + K.nonZeros(), S_.valuePtr());
    for (int i = 0; i < K.rows(); ++i) S_.valuePtr()[diag_[i]] += sigma * (*D.diagonal)[i];
  }
  direct_->setup(S_, same ? SetupKind::Values : SetupKind::Structure, SetupContext{});
  analysed_ = true;
  return direct_->preconditioner() != nullptr;  // a factor exists: S is positive definite
}

namespace {
// σ's bracket [lo, hi] before any factorisation (hi = +inf: unknown).
void bracket(const SparseMatrix& K, const RegionNorm& D, const Vector& g, double radius, double& lo, double& hi) {
  lo = 0;
  hi = INFINITY;
  if (!D.diagonal) return;
  const Vector& d = *D.diagonal;
  double gD = 0, hinf = 0, dmin = INFINITY;  // in y = D^½p: Ĥ = D^-½KD^-½, ĝ = D^-½g
  for (long i = 0; i < g.size(); ++i) {
    gD += g[i] * g[i] / d[i];
    double row = 0;
    for (SparseMatrix::InnerIterator it(K, i); it; ++it) {
      row += std::abs(it.value()) / std::sqrt(d[i] * d[it.col()]);
      if (it.col() == i) dmin = std::min(dmin, it.value() / d[i]);
    }
    hinf = std::max(hinf, row);
  }
  gD = std::sqrt(gD);
  lo = std::max({0.0, -dmin, gD / radius - hinf});
  hi = std::max(0.0, gD / radius + hinf);
}

// The next shift inside (lo, hi) where Newton's step left the bracket (or grown where hi is unknown).
double inside(double lo, double hi) {
  if (!std::isfinite(hi)) return std::max(4 * lo, lo + 1);
  return std::max(std::sqrt(lo * hi), lo + 0.01 * (hi - lo));
}
}  // namespace

MoreSorensenResult MoreSorensen::solve(const SparseMatrix& K, const RegionNorm& D, const Vector& g, double radius,
                                       const Vector* u) {
  if (!(radius > 0)) throw Error("More-Sorensen: the trust-region radius must be > 0");
  const long n = g.size();
  if (K.rows() != n || (D.diagonal ? D.diagonal->size() : D.matrix->rows()) != n)
    throw Error("More-Sorensen: K, D and g differ in size");
  double lo, hi;
  bracket(K, D, g, radius, lo, hi);
  Vector Ku;
  double uKu = 0, uDu = 0;
  const bool has_u = u && u->size() == n;
  if (has_u) {
    uKu = spmv_dot(K, *u, Ku);
    uDu = D.dot(*u, *u);
    if (uDu > 0 && uKu < 0) lo = std::max(lo, -uKu / uDu);
  }
  MoreSorensenResult out;
  Vector p, Dp, w, best;
  double best_sigma = 0, best_norm = 0, sigma = lo;
  bool have_best = false;
  while (out.factorisations < max_factorisations_) {
    ++out.factorisations;
    if (!factorise(K, D, sigma)) {
      ++out.failed;
      lo = std::max(lo, sigma);
      sigma = inside(lo, hi);
      continue;
    }
    direct_->solve(-g, p);
    D.apply(p, Dp);
    const double np = std::sqrt(std::max(0.0, dot(p, Dp)));
    if (np <= (1 + kappa_) * radius) best = p, best_sigma = sigma, best_norm = np, have_best = true;
    if ((sigma == 0 && np <= radius) || std::abs(np - radius) <= kappa_ * radius) break;
    if (np < radius) {
      hi = sigma;
      if (has_u && uDu > 0) {  // the hard case: along u to the boundary, if its curvature is small
        const double pDu = dot(Dp, *u);
        const double sign = pDu >= 0 ? 1 : -1;  // the linear term −στ uᵀDp ≤ 0
        const double tau = sign * step_to_boundary(np * np, sign * pDu, uDu, radius);
        Vector Kp;
        const double pSp = spmv_dot(K, p, Kp) + sigma * np * np;
        if (tau * tau * (uKu + sigma * uDu) <= kappa_ * (2 - kappa_) * std::max(pSp + sigma * radius * radius, 0.0)) {
          best = p + tau * *u, best_sigma = sigma, best_norm = radius, have_best = true;
          out.hard_case = true;
          break;
        }
      }
    } else {
      lo = sigma;
    }
    direct_->solve(Dp, w);  // σ ← σ + (‖p‖/‖q‖)²(‖p‖ − Δ)/Δ, ‖q‖² = (Dp)ᵀ(K + σD)⁻¹(Dp)
    double next = sigma + (np * np / dot(Dp, w)) * (np - radius) / radius;
    if (!(next > lo && next < hi)) next = inside(lo, hi);
    if (std::isfinite(hi) && hi - lo <= 1e-12 * hi) break;
    sigma = next;
  }
  if (!have_best && p.size() == n && out.factorisations > out.failed) {  // only steps too long: cut to the boundary
    const double np = std::sqrt(D.dot(p, p));
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
