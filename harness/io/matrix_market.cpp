#include "matrix_market.hpp"

#include "atomic_file.hpp"

#include "../../core/error.hpp"

#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <vector>

namespace xb {

namespace {

// Reads the next line that is not a Matrix Market comment.
bool next_data_line(std::istream& in, std::string& line, int& lineno) {
  while (std::getline(in, line)) {
    ++lineno;
    if (line.empty() || line[0] == '%') continue;
    return true;
  }
  return false;
}

std::string lower(std::string s) {
  for (auto& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

}  // namespace

void write_matrix_market(TmpFile& out, const SparseMatrix& A) {
  out.write_text([&](std::FILE* f) {
    long long lower_nnz = 0;
    for (int i = 0; i < A.outerSize(); ++i)
      for (SparseMatrix::InnerIterator it(A, i); it; ++it)
        if (it.col() <= i) ++lower_nnz;
    std::fprintf(f, "%%%%MatrixMarket matrix coordinate real symmetric\n");
    std::fprintf(f, "%% xpbd-bench symmetric system matrix (lower triangle, 1-based)\n");
    std::fprintf(f, "%lld %lld %lld\n", static_cast<long long>(A.rows()), static_cast<long long>(A.cols()), lower_nnz);
    for (int i = 0; i < A.outerSize(); ++i)
      for (SparseMatrix::InnerIterator it(A, i); it; ++it)
        if (it.col() <= i) std::fprintf(f, "%d %d %.17g\n", i + 1, static_cast<int>(it.col()) + 1, it.value());
  });
}

void write_matrix_market(TmpFile& out, const Vector& b) {
  out.write_text([&](std::FILE* f) {
    std::fprintf(f, "%%%%MatrixMarket matrix array real general\n");
    std::fprintf(f, "%% xpbd-bench dual system right-hand side b\n");
    std::fprintf(f, "%lld 1\n", static_cast<long long>(b.size()));
    for (long i = 0; i < b.size(); ++i) std::fprintf(f, "%.17g\n", b[i]);
  });
}

void write_matrix_market(const std::string& path, const SparseMatrix& A) {
  make_parent(path);
  TmpFile out(path);
  write_matrix_market(out, A);
  out.commit();
}

void write_matrix_market(const std::string& path, const Vector& b) {
  make_parent(path);
  TmpFile out(path);
  write_matrix_market(out, b);
  out.commit();
}

SparseMatrix read_matrix_market_matrix(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw Error(path + ": cannot open");
  std::string header;
  std::getline(in, header);
  const std::string h = lower(header);
  if (h.rfind("%%matrixmarket matrix coordinate real", 0) != 0)
    throw Error(path + ":1: expected '%%MatrixMarket matrix coordinate real ...'");
  const bool symmetric = h.find("symmetric") != std::string::npos;
  if (!symmetric && h.find("general") == std::string::npos) throw Error(path + ":1: only symmetric or general matrices");
  std::string line;
  int lineno = 1;
  if (!next_data_line(in, line, lineno)) throw Error(path + ": missing size line");
  long long rows = 0, cols = 0, nnz = 0;
  if (std::sscanf(line.c_str(), "%lld %lld %lld", &rows, &cols, &nnz) != 3 || rows < 0 || cols < 0 || nnz < 0)
    throw Error(path + ":" + std::to_string(lineno) + ": bad size line");
  std::vector<Eigen::Triplet<double, int>> t;
  t.reserve(symmetric ? 2 * nnz : nnz);
  for (long long k = 0; k < nnz; ++k) {
    if (!next_data_line(in, line, lineno)) throw Error(path + ": expected " + std::to_string(nnz) + " entries, file ends after " + std::to_string(k));
    long long i = 0, j = 0;
    double v = 0;
    char* end = nullptr;
    if (std::sscanf(line.c_str(), "%lld %lld", &i, &j) != 2) throw Error(path + ":" + std::to_string(lineno) + ": bad entry");
    // The value with strtod (exact round trip of %.17g).
    const char* p = line.c_str();
    for (int field = 0; field < 2; ++field) {
      while (*p == ' ' || *p == '\t') ++p;
      while (*p && *p != ' ' && *p != '\t') ++p;
    }
    v = std::strtod(p, &end);
    if (end == p || i < 1 || j < 1 || i > rows || j > cols)
      throw Error(path + ":" + std::to_string(lineno) + ": bad entry");
    t.emplace_back(static_cast<int>(i - 1), static_cast<int>(j - 1), v);
    if (symmetric && i != j) t.emplace_back(static_cast<int>(j - 1), static_cast<int>(i - 1), v);
  }
  SparseMatrix A(rows, cols);
  A.setFromTriplets(t.begin(), t.end());
  A.makeCompressed();
  return A;
}

Vector read_matrix_market_vector(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw Error(path + ": cannot open");
  std::string header;
  std::getline(in, header);
  if (lower(header).rfind("%%matrixmarket matrix array real general", 0) != 0)
    throw Error(path + ":1: expected '%%MatrixMarket matrix array real general'");
  std::string line;
  int lineno = 1;
  if (!next_data_line(in, line, lineno)) throw Error(path + ": missing size line");
  long long rows = 0, cols = 0;
  if (std::sscanf(line.c_str(), "%lld %lld", &rows, &cols) != 2 || rows < 0 || cols != 1)
    throw Error(path + ":" + std::to_string(lineno) + ": expected 'N 1'");
  Vector b(rows);
  for (long long k = 0; k < rows; ++k) {
    if (!next_data_line(in, line, lineno)) throw Error(path + ": expected " + std::to_string(rows) + " values");
    char* end = nullptr;
    b[k] = std::strtod(line.c_str(), &end);
    if (end == line.c_str()) throw Error(path + ":" + std::to_string(lineno) + ": bad value");
  }
  return b;
}

}  // namespace xb
