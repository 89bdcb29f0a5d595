// Algorithm 2: down the levels (pre-smooth from zero, restrict the residual), direct solve on the
// coarsest, up the levels (prolongate and add the correction, post-smooth). Loops, no recursion.
#include "vcycle.hpp"

#include "../kernels.hpp"

namespace xb::amg {

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
    residual(*L.A, xl, rhs(l), L.r);
    spmv(L.T.R, L.r, levels_[l + 1].b);
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
#pragma omp parallel for schedule(static)
    for (int i = 0; i < n; ++i) {
      double s = 0;
      for (int k = po[i]; k < po[i + 1]; ++k) s += pv[k] * xc[pc[k]];
      xl[i] += s;
    }
    L.smoother->postsmooth(*L.A, rhs(l), xl);
  }
}

}  // namespace xb::amg
