#pragma once
// Buffered input for the mesh readers: a file or a memory block, transparently decompressed
// when its content starts with the gzip or zstd magic. Tracks the byte offset (in the
// decompressed content) and, for text, the line number, so that every error can say where.

#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "mesh/errors.h"
#include "mesh/mesh_io.h"

namespace meshflow::mesh {

// A source of raw bytes; read() returns 0 at the end.
class ByteSource {
 public:
  virtual ~ByteSource() = default;
  virtual std::size_t read(char* buffer, std::size_t size) = 0;
  // Total size when known up front (uncompressed files, memory), else -1.
  virtual std::int64_t size() const { return -1; }
};

class InputStream {
 public:
  // Opens `path`. \throws IoError when it cannot be opened.
  static InputStream open_file(const std::string& path);
  // Reads from memory (not owned; must outlive the stream).
  static InputStream from_memory(std::span<const std::uint8_t> bytes, const std::string& name);

  InputStream(InputStream&&) = default;
  ~InputStream();

  const std::string& name() const { return name_; }
  Compression compression() const { return compression_; }
  // Uncompressed size when known, else -1 (compressed input).
  std::int64_t known_size() const { return known_size_; }
  std::uint64_t offset() const { return consumed_ + pos_; }
  std::uint64_t line() const { return line_; }

  // Makes at least `n` bytes available (fewer only at the end); returns how many are.
  std::size_t fill(std::size_t n);
  const char* data() const { return buffer_.data() + pos_; }
  std::size_t available() const { return end_ - pos_; }
  void skip(std::size_t n) { pos_ += n; }
  bool at_end() { return fill(1) == 0; }

  // The next line without its terminator (\n or \r\n); false at the end. Counts lines.
  bool next_line(std::string_view& line);

  // Copies exactly n bytes or throws ParseError("... expected N more bytes ...").
  void read_exact(void* out, std::size_t n, const char* what);

  // Errors at the current position: text formats name the line, binary ones the byte.
  [[noreturn]] void fail_line(const std::string& reason) const;
  [[noreturn]] void fail_byte(const std::string& reason, std::uint64_t byte) const;

 private:
  InputStream(std::unique_ptr<ByteSource> source, std::string name);
  void detect_compression();

  std::unique_ptr<ByteSource> source_;
  std::string name_;
  Compression compression_ = Compression::None;
  std::int64_t known_size_ = -1;
  std::vector<char> buffer_;
  std::size_t pos_ = 0, end_ = 0;
  std::uint64_t consumed_ = 0;  // bytes dropped from the buffer's front so far
  std::uint64_t line_ = 0;
  bool eof_ = false;
};

// Numbers in text formats, parsed strictly: the whole token must be a number.
bool parse_float(std::string_view token, double& value);
bool parse_int(std::string_view token, std::int64_t& value);

// Splits off the next whitespace-separated token of `line`; empty at the end.
std::string_view next_token(std::string_view& line);

}  // namespace meshflow::mesh
