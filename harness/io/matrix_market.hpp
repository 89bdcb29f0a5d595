// Matrix Market files of captured systems (system_io.hpp): A and K as "coordinate real symmetric"
// (lower triangle, 1-based, %.17g, so every double reads back bit for bit), b and f as "array real
// general" with one column. Written through NAME.tmp and a rename.
#pragma once

#include "atomic_file.hpp"

#include "../../core/sparse.hpp"

#include <string>

namespace xb {

// A must be symmetric (only its lower triangle is written).
void write_matrix_market(const std::string& path, const SparseMatrix& A);
void write_matrix_market(const std::string& path, const Vector& b);
// The same into a file being written (committed by the caller). Throws WriteError.
void write_matrix_market(TmpFile& out, const SparseMatrix& A);
void write_matrix_market(TmpFile& out, const Vector& b);
// Reads "coordinate real {symmetric|general}" into a full CSR matrix.
SparseMatrix read_matrix_market_matrix(const std::string& path);
// Reads "array real general" with one column.
Vector read_matrix_market_vector(const std::string& path);

}  // namespace xb
