// Hierarchy::vcycle, Algorithm 2: down the levels (pre-smooth from zero, restrict the residual),
// direct solve on the coarsest, up the levels (prolongate and add the correction, post-smooth).
// Loops, no recursion. The same in single precision (amg.precision = single): float copies of
// the levels, the coarsest solve in double.
#include "hierarchy.hpp"

#include "../../core/error.hpp"
#include "../kernels.hpp"

#include <algorithm>
#include <cmath>

#if defined(__SSE__)
#include <xmmintrin.h>
#endif

namespace xb::amg {

namespace {
// Denormal floats flushed to zero (FTZ, and read as zero: DAZ) on every thread of the team for
// the float V-cycle, the caller's mode restored after. K holds entries far below its diagonal
// (3e-37 against 1–1.5e4 on squash bunny:50k); their products with small corrections are float
// denormals, which x86 CPUs handle in microcode: the primal float V-cycle ran 11× slower than
// the double one. They are far below float's round-off, so flushing them changes nothing the
// V-cycle resolves. x86 only (MXCSR); elsewhere the floats keep their denormals.
class FlushDenormals {
 public:
#if defined(__SSE__)
  FlushDenormals() : saved_(_mm_getcsr() & kFtzDaz) { set(kFtzDaz); }
  ~FlushDenormals() { set(saved_); }

 private:
  static constexpr unsigned kFtzDaz = 0x8040;  // MXCSR's flush-to-zero and denormals-are-zero bits
  static void set(unsigned bits) {
#pragma omp parallel
    _mm_setcsr((_mm_getcsr() & ~kFtzDaz) | bits);
  }
  unsigned saved_;
#endif
};

// r = b − A x, then b_c = R r (both parallel over rows on the levels big enough to pay for it);
// by node blocks where the level has them.
template <class S>
void residual_restrict(const Level& L, const CsrOf<S>& A, const CsrOf<S>& R, const VectorOf<S>& x,
                       const VectorOf<S>& b, VectorOf<S>& r, VectorOf<S>& bc) {
  const int n = static_cast<int>(A.rows()), nc = static_cast<int>(R.rows());
  r.resize(n);
  bc.resize(nc);
  if (L.A_blocks && !L.R_blocks.empty()) {
    block_residual(*L.A_blocks, A, x.data(), b.data(), r.data());
    block_multiply(L.R_blocks, R, r.data(), bc.data(), false);
    return;
  }
  const int *ao = A.outerIndexPtr(), *ac = A.innerIndexPtr(), *ro = R.outerIndexPtr(), *rc = R.innerIndexPtr();
  const S *av = A.valuePtr(), *rv = R.valuePtr();
#pragma omp parallel if (n > kMinParallelRows)
  {
#pragma omp for schedule(static)
    for (int i = 0; i < n; ++i) {
      S s = b[i];
      for (int k = ao[i]; k < ao[i + 1]; ++k) s -= av[k] * x[ac[k]];
      r[i] = s;
    }
#pragma omp for schedule(static)
    for (int c = 0; c < nc; ++c) {
      S s = 0;
      for (int k = ro[c]; k < ro[c + 1]; ++k) s += rv[k] * r[rc[k]];
      bc[c] = s;
    }
  }
}

// x += P x_c
template <class S>
void prolongate_add(const Level& L, const CsrOf<S>& P, const VectorOf<S>& xc, VectorOf<S>& x) {
  if (!L.P_blocks.empty()) {
    block_multiply(L.P_blocks, P, xc.data(), x.data(), true);
    return;
  }
  const int n = static_cast<int>(P.rows());
  const int *po = P.outerIndexPtr(), *pc = P.innerIndexPtr();
  const S* pv = P.valuePtr();
#pragma omp parallel for schedule(static) if (n > kMinParallelRows)
  for (int i = 0; i < n; ++i) {
    S s = 0;
    for (int k = po[i]; k < po[i + 1]; ++k) s += pv[k] * xc[pc[k]];
    x[i] += s;
  }
}

// dst = src in float: the values only where the pattern is already there (a refresh). The
// pattern is copied array by array (Eigen's cast<float>() inserts entry by entry: on cloth 256²
// the float copies made at setup cost ~0.1 s with it).
void copy_single(const SparseMatrix& src, CsrOf<float>& dst) {
  const long nnz = src.nonZeros();
  if (dst.rows() != src.rows() || dst.cols() != src.cols() || dst.nonZeros() != nnz) {
    dst.resize(src.rows(), src.cols());
    dst.resizeNonZeros(nnz);
    std::copy_n(src.outerIndexPtr(), src.rows() + 1, dst.outerIndexPtr());
    std::copy_n(src.innerIndexPtr(), nnz, dst.innerIndexPtr());
  }
  const double* v = src.valuePtr();
  float* f = dst.valuePtr();
#pragma omp parallel for schedule(static) if (nnz > kMinParallelRows)
  for (long k = 0; k < nnz; ++k) f[k] = static_cast<float>(v[k]);
}
}  // namespace

void Hierarchy::vcycle(const Vector& b, Vector& x) {
  const int nl = num_levels();
  x.resize(b.size());
  if (nl == 1) {
    coarse_solve(b, x);
    return;
  }
  if (opt_.precision == "single") {
    vcycle_single(b, x);
    return;
  }
  auto rhs = [&](int l) -> const Vector& { return l == 0 ? b : levels_[l].b; };
  auto sol = [&](int l) -> Vector& { return l == 0 ? x : levels_[l].x; };
  for (int l = 0; l + 1 < nl; ++l) {
    Level& L = levels_[l];
    Vector& xl = sol(l);
    xl.resize(L.A->rows());
    L.smoother->presmooth(*L.A, rhs(l), xl, true);
    residual_restrict(L, *L.A, L.T.R, xl, rhs(l), L.r, levels_[l + 1].b);
  }
  coarse_solve(levels_[nl - 1].b, levels_[nl - 1].x);
  for (int l = nl - 2; l >= 0; --l) {
    Level& L = levels_[l];
    prolongate_add(L, L.T.P, levels_[l + 1].x, sol(l));
    L.smoother->postsmooth(*L.A, rhs(l), sol(l));
  }
}

void Hierarchy::make_single(size_t fine_levels) {
  for (size_t l = 0; l + 1 < levels_.size() && l < fine_levels; ++l) {
    Level& L = levels_[l];
    const DiagonalRelaxation<double>* relax = L.smoother->relaxation();
    if (!relax) throw Error("amg.precision=single: the smoother " + L.smoother->name() + " has no single-precision form");
    copy_single(*L.A, L.single.A);
    if (L.single.P.nonZeros() != L.T.P.nonZeros()) {  // a refresh keeps P and R
      copy_single(L.T.P, L.single.P);
      copy_single(L.T.R, L.single.R);
    }
    L.single.relax = to_single(*relax);
  }
}

void Hierarchy::vcycle_single(const Vector& b, Vector& x) {
  // The V-cycle is linear in b: it runs on b/‖b‖∞, so that float's range (1e-38 to 3e38) holds
  // its vectors whatever the units of b, and the result is scaled back.
  const double scale = b.cwiseAbs().maxCoeff();
  if (!(scale > 0) || !std::isfinite(scale)) {
    x = scale == 0 ? Vector::Zero(b.size()) : Vector::Constant(b.size(), scale);
    return;
  }
  const FlushDenormals flush;
  const int nl = num_levels();
  levels_[0].single.b = (b / scale).cast<float>();
  for (int l = 0; l + 1 < nl; ++l) {
    SingleLevel& F = levels_[l].single;
    F.x.resize(F.A.rows());
    F.relax.presmooth(F.A, F.b, F.x, true);
    residual_restrict(levels_[l], F.A, F.R, F.x, F.b, F.r, levels_[l + 1].single.b);
  }
  Level& C = levels_[nl - 1];
  C.b = C.single.b.cast<double>();
  coarse_solve(C.b, C.x);
  C.single.x = C.x.cast<float>();
  for (int l = nl - 2; l >= 0; --l) {
    SingleLevel& F = levels_[l].single;
    prolongate_add(levels_[l], F.P, levels_[l + 1].single.x, F.x);
    F.relax.postsmooth(F.A, F.b, F.x);
  }
  x = scale * levels_[0].single.x.cast<double>();
}

}  // namespace xb::amg
