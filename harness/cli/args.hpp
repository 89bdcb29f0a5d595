// Command-line options of one sub-command: declared flags only, each once unless repeatable.
#pragma once

#include <map>
#include <string>
#include <vector>

namespace xb {

struct FlagSpec {
  std::string name;  // "--scene"
  bool takes_value = true;
  bool repeatable = false;
};

class Args {
 public:
  // Throws xb::Error naming an unknown flag, a missing value or a repeated flag.
  Args(const std::string& command, const std::vector<std::string>& argv, const std::vector<FlagSpec>& spec,
       int max_positional = 0);
  bool has(const std::string& flag) const { return values_.count(flag) > 0; }
  std::string get(const std::string& flag, const std::string& fallback = "") const;
  std::string require(const std::string& flag) const;  // throws if absent
  const std::vector<std::string>& all(const std::string& flag) const;
  const std::vector<std::string>& positional() const { return positional_; }
  double get_double(const std::string& flag, double fallback) const;
  int get_int(const std::string& flag, int fallback) const;

 private:
  std::string command_;
  std::map<std::string, std::vector<std::string>> values_;
  std::vector<std::string> positional_;
};

// "a,b,c" → {"a","b","c"} (empty items dropped).
std::vector<std::string> split_list(const std::string& s);

}  // namespace xb
