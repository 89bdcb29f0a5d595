// Captured dual systems (A, b) on disk, for the linear level of the benchmark.
//  PREFIX.h5:     /A/indptr, /A/indices (int64), /A/data (double): the full CSR matrix (both
//                 triangles, sorted columns); /b (double); root attributes: kind = "dual_system",
//                 scene, frame, substep, iteration, rows, nnz and every parameter of the run that
//                 produced it (the schema is in results/README.md).
//  PREFIX_A.mtx:  Matrix Market "coordinate real symmetric" (lower triangle, 1-based, %.17g, so
//                 every double reads back bit for bit).
//  PREFIX_b.mtx:  Matrix Market "array real general" (one column).
// Every file is written to NAME.tmp and renamed, so a failed capture leaves no partial file.
#pragma once

#include "recorder.hpp"

#include "../problems/sparse.hpp"

#include <map>
#include <string>

namespace xb {

struct CapturedSystem {
  SparseMatrix A;
  Vector b;
  std::map<std::string, AttrValue> attrs;  // scene, frame, iteration, rows, nnz, parameters, ...
};

// Writes PREFIX.h5 with A, b and attrs (rows, nnz and kind are added). Throws xb::Error.
void write_system_h5(const std::string& path, const SparseMatrix& A, const Vector& b,
                     const std::map<std::string, AttrValue>& attrs);
// Reads a file written by write_system_h5; throws xb::Error naming the file and what is wrong
// (missing, not HDF5, not a captured system, inconsistent CSR arrays).
CapturedSystem read_system_h5(const std::string& path);

// Matrix Market: A must be symmetric (only its lower triangle is written).
void write_matrix_market(const std::string& path, const SparseMatrix& A);
void write_matrix_market(const std::string& path, const Vector& b);
// Reads "coordinate real {symmetric|general}" into a full CSR matrix.
SparseMatrix read_matrix_market_matrix(const std::string& path);
// Reads "array real general" with one column.
Vector read_matrix_market_vector(const std::string& path);

// Writes PREFIX.h5, PREFIX_A.mtx and PREFIX_b.mtx.
void write_captured_system(const std::string& prefix, const SparseMatrix& A, const Vector& b,
                           const std::map<std::string, AttrValue>& attrs);

// The attribute as text (integers as integers, doubles with %.17g), "" if absent.
std::string attr_text(const std::map<std::string, AttrValue>& attrs, const std::string& key);

}  // namespace xb
