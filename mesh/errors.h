#pragma once
// The few error types of meshflow (STYLE §4). Bad input throws one of these; programmer errors
// use MESHFLOW_ASSERT. The HTTP layers map them to status codes: InvalidInput and ParseError
// 400, LimitExceeded 413, IoError 500/502.

#include <cstdint>
#include <optional>
#include <stdexcept>
#include <string>

namespace meshflow {

// A broken precondition caused by the caller's input (bad parameter, unknown name...).
class InvalidInput : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Where in a file or document a parse error is. Text formats give line (1-based) and maybe
// column; binary formats give the byte offset (0-based, in the decompressed content).
struct SourceLocation {
  std::string file;
  std::optional<std::uint64_t> line;
  std::optional<std::uint64_t> column;
  std::optional<std::uint64_t> byte_offset;
  std::string to_string() const;  // "file:12:3", "file: byte 4096", "file"
};

// Input that does not follow its format. what() reads "file:line: reason" or
// "file: byte N: reason".
class ParseError : public InvalidInput {
 public:
  ParseError(SourceLocation where, const std::string& reason);
  const SourceLocation& where() const { return where_; }
  const std::string& reason() const { return reason_; }

 private:
  SourceLocation where_;
  std::string reason_;
};

// A resource limit (body size, rows, iterations, memory budget) was exceeded.
class LimitExceeded : public std::runtime_error {
 public:
  LimitExceeded(const std::string& what, std::uint64_t limit, std::uint64_t actual);
  std::uint64_t limit() const { return limit_; }
  std::uint64_t actual() const { return actual_; }

 private:
  std::uint64_t limit_;
  std::uint64_t actual_;
};

// A file or network operation failed (cannot open, short write, connection refused...).
class IoError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

[[noreturn]] void assertion_failed(const char* condition, const char* why, const char* file,
                                   int line);

}  // namespace meshflow

// Programmer errors only: never reachable from user input. Stays on in release builds.
#define MESHFLOW_ASSERT(cond, why) \
  ((cond) ? (void)0 : ::meshflow::assertion_failed(#cond, why, __FILE__, __LINE__))
