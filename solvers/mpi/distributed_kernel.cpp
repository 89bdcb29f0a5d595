#include "distributed_kernel.hpp"

#include <numeric>

namespace xb {

void DistributedKernel::record_setup(const std::string& action, bool full) {
  action_ = action;
  ++(full ? full_setups_ : reused_setups_);
}

void DistributedKernel::record_levels(std::vector<double> rows, std::vector<double> nnz) {
  level_rows_ = std::move(rows);
  level_nnz_ = std::move(nnz);
}

std::map<std::string, double> DistributedKernel::statistics() const {
  const auto sum = [](const std::vector<double>& v) { return std::accumulate(v.begin(), v.end(), 0.0); };
  const bool any = !level_rows_.empty() && level_rows_[0] > 0 && level_nnz_[0] > 0;
  return {{"levels", static_cast<double>(level_rows_.size())},
          {"operator_complexity", any ? sum(level_nnz_) / level_nnz_[0] : 0},
          {"grid_complexity", any ? sum(level_rows_) / level_rows_[0] : 0},
          {"setup_full", static_cast<double>(full_setups_)},
          {"setup_reused", static_cast<double>(reused_setups_)}};
}

std::map<std::string, std::vector<double>> DistributedKernel::array_statistics() const {
  return {{"level_rows", level_rows_}, {"level_nnz", level_nnz_}};
}

}  // namespace xb
