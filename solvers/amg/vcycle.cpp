// Hierarchy::vcycle, Algorithm 2: down the levels (pre-smooth from zero, restrict the residual),
// direct solve on the coarsest, up the levels (prolongate and add the correction, post-smooth).
// Loops, no recursion.
#include "hierarchy.hpp"

#include "../kernels.hpp"

namespace xb::amg {

namespace {
// r = b − A x, then b_c = R r (both parallel over rows on the levels big enough to pay for it).
void residual_restrict(const SparseMatrix& A, const SparseMatrix& R, const Vector& x, const Vector& b, Vector& r,
                       Vector& bc) {
  const int n = static_cast<int>(A.rows()), nc = static_cast<int>(R.rows());
  const int *ao = A.outerIndexPtr(), *ac = A.innerIndexPtr(), *ro = R.outerIndexPtr(), *rc = R.innerIndexPtr();
  const double *av = A.valuePtr(), *rv = R.valuePtr();
  r.resize(n);
  bc.resize(nc);
#pragma omp parallel if (n > kMinParallelRows)
  {
#pragma omp for schedule(static)
    for (int i = 0; i < n; ++i) {
      double s = b[i];
      for (int k = ao[i]; k < ao[i + 1]; ++k) s -= av[k] * x[ac[k]];
      r[i] = s;
    }
#pragma omp for schedule(static)
    for (int c = 0; c < nc; ++c) {
      double s = 0;
      for (int k = ro[c]; k < ro[c + 1]; ++k) s += rv[k] * r[rc[k]];
      bc[c] = s;
    }
  }
}
}  // namespace

void Hierarchy::vcycle(const Vector& b, Vector& x) {
  const int nl = num_levels();
  x.resize(b.size());
  if (nl == 1) {
    coarse_solve(b, x);
    return;
  }
  auto rhs = [&](int l) -> const Vector& { return l == 0 ? b : levels_[l].b; };
  auto sol = [&](int l) -> Vector& { return l == 0 ? x : levels_[l].x; };
  for (int l = 0; l + 1 < nl; ++l) {
    Level& L = levels_[l];
    Vector& xl = sol(l);
    xl.resize(L.A->rows());
    L.smoother->presmooth(*L.A, rhs(l), xl, true);
    residual_restrict(*L.A, L.T.R, xl, rhs(l), L.r, levels_[l + 1].b);
  }
  coarse_solve(levels_[nl - 1].b, levels_[nl - 1].x);
  for (int l = nl - 2; l >= 0; --l) {
    Level& L = levels_[l];
    Vector& xl = sol(l);
    const Vector& xc = levels_[l + 1].x;
    const int n = static_cast<int>(L.T.P.rows());
    const int* po = L.T.P.outerIndexPtr();
    const int* pc = L.T.P.innerIndexPtr();
    const double* pv = L.T.P.valuePtr();
#pragma omp parallel for schedule(static) if (n > kMinParallelRows)
    for (int i = 0; i < n; ++i) {
      double s = 0;
      for (int k = po[i]; k < po[i + 1]; ++k) s += pv[k] * xc[pc[k]];
      xl[i] += s;
    }
    L.smoother->postsmooth(*L.A, rhs(l), xl);
  }
}

}  // namespace xb::amg
