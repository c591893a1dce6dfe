#include "mesh/errors.h"

#include <cstdio>
#include <cstdlib>

namespace meshflow {

std::string SourceLocation::to_string() const {
  std::string out = file.empty() ? std::string("<input>") : file;
  if (line) {
    out += ":" + std::to_string(*line);
    if (column) out += ":" + std::to_string(*column);
  } else if (byte_offset) {
    out += ": byte " + std::to_string(*byte_offset);
  }
  return out;
}

ParseError::ParseError(SourceLocation where, const std::string& reason)
    : InvalidInput(where.to_string() + ": " + reason), where_(std::move(where)), reason_(reason) {}

LimitExceeded::LimitExceeded(const std::string& what, std::uint64_t limit, std::uint64_t actual)
    : std::runtime_error(what + " (limited to " + std::to_string(limit) + ", found " +
                         std::to_string(actual) + ")"),
      limit_(limit),
      actual_(actual) {}

void assertion_failed(const char* condition, const char* why, const char* file, int line) {
  std::fprintf(stderr, "meshflow: internal error at %s:%d: %s (%s)\n", file, line, why, condition);
  std::abort();
}

}  // namespace meshflow
