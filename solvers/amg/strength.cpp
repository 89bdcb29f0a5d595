#include "strength.hpp"

#include "../../core/error.hpp"
#include "../kernels.hpp"

#include <cmath>
#include <vector>

namespace xb::amg {

SparseMatrix strength_symmetric(const SparseMatrix& A, double theta) {
  if (!(theta >= 0)) throw Error("amg.strength_threshold must be >= 0 (got " + std::to_string(theta) + ")");
  if (A.rows() != A.cols()) throw Error("strength of connection needs a square matrix");
  const int n = static_cast<int>(A.rows());
  const int* outer = A.outerIndexPtr();
  const int* cols = A.innerIndexPtr();
  const double* val = A.valuePtr();
  const Vector d = diagonal(A);
  const double t2 = theta * theta;
  // Compare squares (as pyamg does) so θ = 0 keeps explicit zeros too: the pattern, not the
  // values, is what "keeps everything" means.
  auto strong = [&](int i, int k) {
    const int j = cols[k];
    return j == i || val[k] * val[k] >= t2 * std::abs(d[i] * d[j]);
  };
  std::vector<int> count(n + 1, 0);
#pragma omp parallel for schedule(static)
  for (int i = 0; i < n; ++i) {
    int c = 0;
    for (int k = outer[i]; k < outer[i + 1]; ++k) c += strong(i, k);
    count[i + 1] = c;
  }
  for (int i = 0; i < n; ++i) count[i + 1] += count[i];
  SparseMatrix S(n, n);
  S.resizeNonZeros(count[n]);
  int* so = S.outerIndexPtr();
  int* sc = S.innerIndexPtr();
  double* sv = S.valuePtr();
#pragma omp parallel for schedule(static)
  for (int i = 0; i <= n; ++i) so[i] = count[i];
#pragma omp parallel for schedule(static)
  for (int i = 0; i < n; ++i) {
    int p = count[i];
    for (int k = outer[i]; k < outer[i + 1]; ++k)
      if (strong(i, k)) {
        sc[p] = cols[k];
        sv[p] = val[k];
        ++p;
      }
  }
  return S;
}

}  // namespace xb::amg
