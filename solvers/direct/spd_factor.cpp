#include "spd_factor.hpp"

#include <cholmod.h>

#include <algorithm>

namespace xb {

struct SpdFactor::State {
  cholmod_common c{};
  cholmod_factor* L = nullptr;
  bool ok = false;
  long rows = -1, nonzeros = -1;  // of the matrix L's analysis is of
};

SpdFactor::SpdFactor() : s_(std::make_unique<State>()) {
  cholmod_start(&s_->c);
  s_->c.supernodal = CHOLMOD_SUPERNODAL;  // LLᵀ always: its success is the proof
  s_->c.final_ll = 1;
  s_->c.quick_return_if_not_posdef = 1;
  s_->c.print = 0;
}

SpdFactor::~SpdFactor() {
  if (s_->L) cholmod_free_factor(&s_->L, &s_->c);
  cholmod_finish(&s_->c);
}

bool SpdFactor::factorise(const SparseMatrix& K, std::string& why) {
  cholmod_sparse view{};
  view.nrow = view.ncol = K.rows();
  view.nzmax = K.nonZeros();
  view.p = const_cast<int*>(K.outerIndexPtr());
  view.i = const_cast<int*>(K.innerIndexPtr());
  view.x = const_cast<double*>(K.valuePtr());
  view.stype = 1;  // a row-major CSR of a symmetric matrix read as CSC: its upper triangle
  view.itype = CHOLMOD_INT;
  view.xtype = CHOLMOD_REAL;
  view.dtype = CHOLMOD_DOUBLE;
  view.sorted = 1;
  view.packed = 1;
  cholmod_common& c = s_->c;
  if (s_->L && (s_->rows != K.rows() || s_->nonzeros != K.nonZeros())) cholmod_free_factor(&s_->L, &c);
  if (!s_->L) {  // the analysis (ordering, supernodes) once per pattern
    s_->L = cholmod_analyze(&view, &c);
    s_->rows = K.rows();
    s_->nonzeros = K.nonZeros();
  }
  s_->ok = s_->L && cholmod_factorize(&view, s_->L, &c) && c.status == CHOLMOD_OK && s_->L->is_ll;
  if (s_->ok) return true;
  if (c.status == CHOLMOD_NOT_POSDEF && s_->L)
    why = "not positive definite: CHOLMOD's LL^T stopped at column " + std::to_string(s_->L->minor) + " of " +
          std::to_string(K.rows());
  else if (c.status == CHOLMOD_OUT_OF_MEMORY)
    why = "out of memory in CHOLMOD's factorisation";
  else
    why = "CHOLMOD failed (status " + std::to_string(c.status) + ")";
  return false;
}

void SpdFactor::release() {
  // Back to the symbolic factor: the numbers go, the analysis stays for the next factorise().
  if (s_->L && !cholmod_change_factor(CHOLMOD_PATTERN, 1, 1, 1, 1, s_->L, &s_->c)) cholmod_free_factor(&s_->L, &s_->c);
  s_->ok = false;
}

bool SpdFactor::solve(const Vector& b, Vector& x) {
  if (!s_->ok) return false;
  cholmod_dense bd{};
  bd.nrow = b.size();
  bd.ncol = 1;
  bd.nzmax = b.size();
  bd.d = b.size();
  bd.x = const_cast<double*>(b.data());
  bd.xtype = CHOLMOD_REAL;
  bd.dtype = CHOLMOD_DOUBLE;
  cholmod_dense* xd = cholmod_solve(CHOLMOD_A, s_->L, &bd, &s_->c);
  if (!xd) return false;
  x.resize(b.size());
  std::copy(static_cast<double*>(xd->x), static_cast<double*>(xd->x) + b.size(), x.data());
  cholmod_free_dense(&xd, &s_->c);
  return true;
}

}  // namespace xb
