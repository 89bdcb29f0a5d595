// Captured systems on disk, for the linear level of the benchmark: the dual system (A, b) and
// what its primal form needs (J, inverse masses, α̃, positions).
//  PREFIX.h5:     /A/indptr, /A/indices (int64), /A/data (double): the full CSR matrix (both
//                 triangles, sorted columns); /b (double); /J/indptr, /J/indices, /J/data: ∇C as
//                 an m × 3n CSR matrix (columns 3p..3p+2 = particle p, every particle of a
//                 constraint stored, pinned ones too); /inverse_mass (n), /alpha_tilde (m),
//                 /positions (3n, particle-major); root attributes: kind = "dual_system", scene,
//                 frame, substep, iteration, rows, nnz and every parameter of the run that produced
//                 it (the schema is in results/README.md). Files captured before the primal form
//                 existed have no /J: only the dual form can be solved on them.
//  PREFIX_A.mtx:  Matrix Market "coordinate real symmetric" (lower triangle, 1-based, %.17g, so
//                 every double reads back bit for bit); PREFIX_K.mtx the same for the primal K.
//  PREFIX_b.mtx:  Matrix Market "array real general" (one column); PREFIX_f.mtx: K's right-hand side.
// Every file is written to NAME.tmp and renamed, so a failed capture leaves no partial file.
#pragma once

#include "atomic_file.hpp"
#include "matrix_market.hpp"
#include "record.hpp"

#include "../../problems/primal_system.hpp"
#include "../../core/sparse.hpp"

#include <map>
#include <string>
#include <vector>

namespace xb {

struct CapturedSystem {
  SparseMatrix A;
  Vector b;
  std::map<std::string, AttrValue> attrs;  // scene, frame, iteration, rows, nnz, parameters, ...
  // The primal form's data; empty for files captured before it existed.
  ConstraintGraph graph;  // each constraint's particles, the inverse masses
  Gradients grad;
  Eigen::VectorXd alpha_tilde;
  Eigen::Matrix3Xd x;
  bool has_primal() const { return !graph.particles.empty() && grad.size() == graph.particles.size(); }
};

// ∇C as an m × 3n CSR matrix (every particle of a constraint, pinned ones too), and back:
// jacobian_from_csr() throws xb::Error for a row with more than 4 particles.
SparseMatrix jacobian_csr(const ConstraintGraph& graph, const Gradients& grad);
void jacobian_from_csr(const SparseMatrix& J, ConstraintGraph& graph, Gradients& grad);

// Writes PREFIX.h5 with A, b, the primal data (if present) and attrs (rows, nnz and kind are
// added), atomically, or into `out` (committed by the caller). Throws xb::Error (WriteError for
// a failed write).
void write_system_h5(const std::string& path, const CapturedSystem& sys);
void write_system_h5(TmpFile& out, const CapturedSystem& sys);
// Reads a file written by write_system_h5; throws xb::Error naming the file and what is wrong
// (missing, not HDF5, not a captured system, inconsistent CSR arrays).
CapturedSystem read_system_h5(const std::string& path);

// Writes PREFIX.h5, PREFIX_A.mtx and PREFIX_b.mtx, and PREFIX_K.mtx and PREFIX_f.mtx when the
// system has its primal data and every α̃ > 0: all to their .tmp files first, then renamed (a
// failed write leaves every earlier file of PREFIX as it was). Returns the paths written.
std::vector<std::string> write_captured_system(const std::string& prefix, const CapturedSystem& sys);

// The attribute as text (integers as integers, doubles with %.17g), "" if absent.
std::string attr_text(const std::map<std::string, AttrValue>& attrs, const std::string& key);

}  // namespace xb
