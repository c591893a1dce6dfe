#pragma once
// Fixed-size binary records in scratch files of the out-of-core partition: appended through a
// buffer per file (one file open at a time, whatever the number of parts), read back whole
// (a file holds one part's records, so it fits). Little-endian, host layout.

#include <cstdint>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include "mesh/errors.h"

namespace meshflow::parallel {

template <typename Record>
class Buckets {
 public:
  Buckets(std::string prefix, std::size_t buckets, std::size_t buffer_records = 4096)
      : prefix_(std::move(prefix)), buffers_(buckets), counts_(buckets, 0), limit_(buffer_records) {}
  ~Buckets() {
    try {
      flush();
    } catch (...) {
    }
  }
  std::string path(std::size_t b) const { return prefix_ + std::to_string(b) + ".bin"; }
  void add(std::size_t b, const Record& r) {
    buffers_[b].push_back(r);
    ++counts_[b];
    if (buffers_[b].size() >= limit_) flush(b);
  }
  void flush() {
    for (std::size_t b = 0; b < buffers_.size(); ++b) flush(b);
  }
  std::uint64_t count(std::size_t b) const { return counts_[b]; }

 private:
  void flush(std::size_t b) {
    if (buffers_[b].empty()) return;
    std::FILE* f = std::fopen(path(b).c_str(), "ab");
    if (!f) throw IoError(path(b) + ": cannot open for appending");
    std::size_t n = std::fwrite(buffers_[b].data(), sizeof(Record), buffers_[b].size(), f);
    if (std::fclose(f) != 0 || n != buffers_[b].size()) throw IoError(path(b) + ": cannot write (disk full?)");
    buffers_[b].clear();
  }
  std::string prefix_;
  std::vector<std::vector<Record>> buffers_;
  std::vector<std::uint64_t> counts_;
  std::size_t limit_;
};

// A missing file is an empty one. \throws ParseError when the size is not a whole number of records.
template <typename Record>
std::vector<Record> load_records(const std::string& path) {
  std::vector<Record> out;
  std::FILE* f = std::fopen(path.c_str(), "rb");
  if (!f) return out;
  std::fseek(f, 0, SEEK_END);
  long size = std::ftell(f);
  std::fseek(f, 0, SEEK_SET);
  if (size < 0 || size % sizeof(Record) != 0) {
    std::fclose(f);
    throw ParseError({.file = path, .line = {}, .column = {}, .byte_offset = static_cast<std::uint64_t>(size < 0 ? 0 : size)},
                     "not a whole number of " + std::to_string(sizeof(Record)) + "-byte records");
  }
  out.resize(size / sizeof(Record));
  std::size_t n = std::fread(out.data(), sizeof(Record), out.size(), f);
  std::fclose(f);
  if (n != out.size()) throw IoError(path + ": cannot read");
  return out;
}

}  // namespace meshflow::parallel
