// What the ASCII mesh readers share: the whole file as lines of tokens with line numbers, and
// number parsing whose errors name FILE:LINE and what was being read.
#pragma once

#include "../../core/error.hpp"

#include <charconv>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <string_view>
#include <vector>

namespace xb::mesh_text {

inline std::string read_whole(const std::string& path) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) throw Error(path + ": is a directory, not a mesh file");
  if (!std::filesystem::is_regular_file(path, ec)) throw Error(path + ": no such mesh file");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error(path + ": cannot open");
  std::ostringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

// Line-oriented reading with line numbers; '#' starts a comment when `comments` is set.
class Lines {
 public:
  Lines(std::string path, bool comments) : path_(std::move(path)), text_(read_whole(path_)), comments_(comments) {
    if (text_.find('\0') != std::string::npos)
      throw Error(path_ + ": contains NUL bytes (a binary file? only ASCII meshes are read)");
  }
  const std::string& path() const { return path_; }
  // Nothing but whitespace after the current line.
  bool at_end() const { return text_.find_first_not_of(" \t\r\n\v\f", pos_) == std::string::npos; }
  int line() const { return line_; }
  std::string where() const { return path_ + ":" + std::to_string(line_); }
  std::string where(int line) const { return path_ + ":" + std::to_string(line); }

  // The tokens of the next line that has any (blank and comment-only lines are skipped).
  // Returns false at the end of the file.
  bool next(std::vector<std::string_view>& tokens) {
    tokens.clear();
    while (pos_ < text_.size()) {
      size_t end = text_.find('\n', pos_);
      if (end == std::string::npos) end = text_.size();
      std::string_view l(text_.data() + pos_, end - pos_);
      pos_ = end + 1;
      ++line_;
      if (comments_) {
        const size_t h = l.find('#');
        if (h != std::string_view::npos) l = l.substr(0, h);
      }
      size_t i = 0;
      while (i < l.size()) {
        while (i < l.size() && is_space(l[i])) ++i;
        size_t j = i;
        while (j < l.size() && !is_space(l[j])) ++j;
        if (j > i) tokens.push_back(l.substr(i, j - i));
        i = j;
      }
      if (!tokens.empty()) return true;
    }
    return false;
  }
  // As next(), but the end of the file is an error: "truncated while reading <what>".
  // A gmsh section's end marker where an entry should be: the declared count is larger than the data.
  void require(std::vector<std::string_view>& tokens, const std::string& what) {
    if (!next(tokens))
      throw Error(where() + ": file ends early (truncated?) while reading " + what + " (is a declared count larger than the data?)");
    if (tokens[0].starts_with("$End") && !what.starts_with("$End"))
      throw Error(where() + ": the section ends ('" + std::string(tokens[0]) + "') while reading " + what +
                  ": the declared count is larger than the data");
  }
  // A single token stream across lines (medit), with the line of the last token.
  bool next_token(std::string_view& tok) {
    while (tok_i_ >= tok_buf_.size()) {
      if (!next(tok_buf_)) return false;
      tok_i_ = 0;
    }
    tok = tok_buf_[tok_i_++];
    return true;
  }
  std::string_view require_token(const std::string& what) {
    std::string_view t;
    if (!next_token(t)) throw Error(where() + ": file ends early (truncated?) while reading " + what);
    return t;
  }

 private:
  static bool is_space(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f'; }
  std::string path_, text_;
  bool comments_;
  size_t pos_ = 0;
  int line_ = 0;
  std::vector<std::string_view> tok_buf_;
  size_t tok_i_ = 0;
};

inline long long parse_int(std::string_view t, const std::string& where, const std::string& what) {
  long long v = 0;
  const char* b = t.data();
  const char* e = t.data() + t.size();
  if (!t.empty() && *b == '+') ++b;
  auto [p, ec] = std::from_chars(b, e, v);
  if (ec != std::errc() || p != e)
    throw Error(where + ": " + what + " '" + std::string(t) + "' is not an integer");
  return v;
}

inline double parse_double(std::string_view t, const std::string& where, const std::string& what) {
  const std::string s(t);
  char* end = nullptr;
  const double v = std::strtod(s.c_str(), &end);
  if (s.empty() || end != s.c_str() + s.size()) throw Error(where + ": " + what + " '" + s + "' is not a number");
  if (!std::isfinite(v)) throw Error(where + ": " + what + " '" + s + "' is not a finite number");
  return v;
}

// A declared count: non-negative and not larger than the file could hold (so a corrupt count
// cannot trigger a huge allocation).
inline long long parse_count(std::string_view t, const std::string& where, const std::string& what, size_t file_bytes) {
  const long long n = parse_int(t, where, what);
  if (n < 0) throw Error(where + ": " + what + " " + std::to_string(n) + " is negative");
  if (static_cast<unsigned long long>(n) > file_bytes / 2 + 1)
    throw Error(where + ": " + what + " " + std::to_string(n) + " is more than the file can hold (wrong count?)");
  return n;
}

inline void expect_tokens(const Lines& L, const std::vector<std::string_view>& tok, size_t n, const std::string& what) {
  if (tok.size() != n)
    throw Error(L.where() + ": " + what + ": expected " + std::to_string(n) + " values, found " + std::to_string(tok.size()) +
                (L.at_end() && tok.size() < n ? " (the file ends here: truncated?)" : ""));
}

inline size_t file_size(const std::string& path) {
  std::error_code ec;
  const auto s = std::filesystem::file_size(path, ec);
  return ec ? 0 : static_cast<size_t>(s);
}

}  // namespace xb::mesh_text
