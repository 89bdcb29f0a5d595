// A Cholesky factorisation that proves positive definiteness (the certificate of a reference,
// harness/sim/certificate.hpp): CHOLMOD held to its supernodal LLᵀ. The solver `cholmod` leaves
// CHOLMOD its choice, and for small matrices that is the simplicial LDLᵀ, which factorises some
// indefinite matrices (a negative D); LLᵀ stops at the first column whose pivot is not positive.
#pragma once

#include "../../core/sparse.hpp"

#include <memory>
#include <string>

namespace xb {

class SpdFactor {
 public:
  SpdFactor();
  ~SpdFactor();
  SpdFactor(const SpdFactor&) = delete;
  SpdFactor& operator=(const SpdFactor&) = delete;
  // Factorises K (symmetric, both triangles stored; the upper one is read). True: K is positive
  // definite. False with `why` where it is not (the column CHOLMOD stopped at) or CHOLMOD failed.
  // The symbolic analysis is kept for the next K of the same pattern (rows and non-zeros).
  bool factorise(const SparseMatrix& K, std::string& why);
  // x = K⁻¹b with the last successful factorisation; false if CHOLMOD failed.
  bool solve(const Vector& b, Vector& x);
  // Frees the factor's numbers (the analysis stays).
  void release();

 private:
  struct State;
  std::unique_ptr<State> s_;
};

}  // namespace xb
