#include "mesh/input_stream.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>
#include <zlib.h>
#include <zstd.h>

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstring>

namespace meshflow::mesh {
namespace {

constexpr std::size_t kChunk = 1 << 22;  // 4 MiB reads

class FileSource : public ByteSource {
 public:
  FileSource(int fd, std::int64_t size) : fd_(fd), size_(size) {}
  ~FileSource() override { ::close(fd_); }
  std::size_t read(char* buffer, std::size_t size) override {
    for (;;) {
      ssize_t n = ::read(fd_, buffer, size);
      if (n >= 0) return static_cast<std::size_t>(n);
      if (errno != EINTR) throw IoError(std::string("read failed: ") + std::strerror(errno));
    }
  }
  std::int64_t size() const override { return size_; }

 private:
  int fd_;
  std::int64_t size_;
};

class MemorySource : public ByteSource {
 public:
  explicit MemorySource(std::span<const std::uint8_t> bytes) : bytes_(bytes) {}
  std::size_t read(char* buffer, std::size_t size) override {
    std::size_t n = std::min(size, bytes_.size() - pos_);
    std::memcpy(buffer, bytes_.data() + pos_, n);
    pos_ += n;
    return n;
  }
  std::int64_t size() const override { return static_cast<std::int64_t>(bytes_.size()); }

 private:
  std::span<const std::uint8_t> bytes_;
  std::size_t pos_ = 0;
};

// Gzip (possibly several members) over another source.
class GzipSource : public ByteSource {
 public:
  GzipSource(std::unique_ptr<ByteSource> inner, std::string name)
      : inner_(std::move(inner)), in_(kChunk, '\0'), name_(std::move(name)) {
    std::memset(&z_, 0, sizeof z_);
    if (inflateInit2(&z_, 16 + MAX_WBITS) != Z_OK) throw IoError("zlib init failed");
  }
  ~GzipSource() override { inflateEnd(&z_); }
  std::size_t read(char* buffer, std::size_t size) override {
    z_.next_out = reinterpret_cast<Bytef*>(buffer);
    z_.avail_out = static_cast<uInt>(std::min<std::size_t>(size, 1u << 30));
    while (z_.avail_out > 0) {
      if (z_.avail_in == 0) {
        if (in_used_ > 0) {
          z_.next_in = reinterpret_cast<Bytef*>(in_.data());
          z_.avail_in = static_cast<uInt>(in_used_);
          in_used_ = 0;
        } else {
          std::size_t n = inner_->read(in_.data(), kChunk);
          compressed_ += n;
          if (n == 0) {
            if (!finished_member_) fail("truncated gzip stream", "more compressed data", size);
            break;
          }
          z_.next_in = reinterpret_cast<Bytef*>(in_.data());
          z_.avail_in = static_cast<uInt>(n);
        }
      }
      finished_member_ = false;
      int rc = inflate(&z_, Z_NO_FLUSH);
      if (rc == Z_STREAM_END) {
        finished_member_ = true;
        inflateReset(&z_);  // a following member, if any
      } else if (rc != Z_OK && rc != Z_BUF_ERROR) {
        fail(std::string("corrupt gzip stream (") + (z_.msg ? z_.msg : "inflate failed") + ")",
             "valid deflate data", size);
      }
    }
    produced_ += size - z_.avail_out;
    return size - z_.avail_out;
  }

 private:
  // Where: the byte of the decompressed content reached, and how far into the compressed file.
  [[noreturn]] void fail(const std::string& what, const std::string& expected, std::size_t size) {
    throw ParseError({name_, {}, {}, produced_ + (size - z_.avail_out)},
                     what + " at compressed byte " + std::to_string(compressed_ - z_.avail_in) +
                         ": expected " + expected);
  }
  std::unique_ptr<ByteSource> inner_;
  std::string in_;
  std::size_t in_used_ = 0;
  z_stream z_;
  bool finished_member_ = false;
  std::string name_;
  std::uint64_t compressed_ = 0, produced_ = 0;

 public:
  void set_prefix(const char* data, std::size_t n) {
    std::memcpy(in_.data(), data, n);
    in_used_ = n;
    compressed_ = n;
  }
};

class ZstdSource : public ByteSource {
 public:
  ZstdSource(std::unique_ptr<ByteSource> inner, std::string name)
      : inner_(std::move(inner)), in_(ZSTD_DStreamInSize()), name_(std::move(name)) {
    stream_ = ZSTD_createDStream();
    ZSTD_initDStream(stream_);
  }
  ~ZstdSource() override { ZSTD_freeDStream(stream_); }
  void set_prefix(const char* data, std::size_t n) {
    if (n > in_.size()) in_.resize(n);
    std::memcpy(in_.data(), data, n);
    input_ = {in_.data(), n, 0};
    compressed_ = n;
  }
  std::size_t read(char* buffer, std::size_t size) override {
    ZSTD_outBuffer out{buffer, size, 0};
    while (out.pos < out.size) {
      if (input_.pos == input_.size) {
        std::size_t n = inner_->read(in_.data(), in_.size());
        compressed_ += n;
        if (n == 0) {
          if (!frame_done_) fail("truncated zstd stream", "more compressed data", out.pos);
          break;
        }
        input_ = {in_.data(), n, 0};
      }
      std::size_t rc = ZSTD_decompressStream(stream_, &out, &input_);
      if (ZSTD_isError(rc))
        fail(std::string("corrupt zstd stream (") + ZSTD_getErrorName(rc) + ")", "a valid zstd frame", out.pos);
      frame_done_ = rc == 0;
    }
    produced_ += out.pos;
    return out.pos;
  }

 private:
  std::unique_ptr<ByteSource> inner_;
  std::vector<char> in_;
  ZSTD_inBuffer input_{nullptr, 0, 0};
  ZSTD_DStream* stream_;
  bool frame_done_ = true;
  std::string name_;
  std::uint64_t compressed_ = 0, produced_ = 0;

  // Where: the byte of the decompressed content reached, and how far into the compressed file.
  [[noreturn]] void fail(const std::string& what, const std::string& expected, std::size_t pending) {
    throw ParseError({name_, {}, {}, produced_ + pending},
                     what + " at compressed byte " + std::to_string(compressed_ - (input_.size - input_.pos)) +
                         ": expected " + expected);
  }
};

}  // namespace

InputStream::InputStream(std::unique_ptr<ByteSource> source, std::string name)
    : source_(std::move(source)), name_(std::move(name)) {
  known_size_ = source_->size();
  detect_compression();
}

InputStream::~InputStream() = default;

InputStream InputStream::open_file(const std::string& path) {
  int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) throw IoError(path + ": cannot open: " + std::strerror(errno));
  struct stat st{};
  if (::fstat(fd, &st) != 0 || S_ISDIR(st.st_mode)) {
    ::close(fd);
    throw IoError(path + ": not a regular file");
  }
  ::posix_fadvise(fd, 0, 0, POSIX_FADV_SEQUENTIAL);
  return InputStream(std::make_unique<FileSource>(fd, static_cast<std::int64_t>(st.st_size)), path);
}

InputStream InputStream::from_memory(std::span<const std::uint8_t> bytes, const std::string& name) {
  return InputStream(std::make_unique<MemorySource>(bytes), name);
}

void InputStream::detect_compression() {
  // Peek at the raw bytes: the magic decides, whatever the extension says. Small inputs get
  // a small buffer (fill() grows it when decompressed content needs more).
  std::size_t initial = known_size_ >= 0 ? static_cast<std::size_t>(known_size_) + 64 : kChunk;
  buffer_.resize(std::clamp<std::size_t>(initial, 64, kChunk));
  std::size_t n = 0;
  while (n < 4) {
    std::size_t got = source_->read(buffer_.data() + n, 4 - n);
    if (got == 0) break;
    n += got;
  }
  auto* b = reinterpret_cast<const unsigned char*>(buffer_.data());
  if (n >= 2 && b[0] == 0x1f && b[1] == 0x8b) {
    compression_ = Compression::Gzip;
    auto gz = std::make_unique<GzipSource>(std::move(source_), name_);
    gz->set_prefix(buffer_.data(), n);
    source_ = std::move(gz);
    known_size_ = -1;
    n = 0;
  } else if (n >= 4 && b[0] == 0x28 && b[1] == 0xb5 && b[2] == 0x2f && b[3] == 0xfd) {
    compression_ = Compression::Zstd;
    auto zs = std::make_unique<ZstdSource>(std::move(source_), name_);
    zs->set_prefix(buffer_.data(), n);
    source_ = std::move(zs);
    known_size_ = -1;
    n = 0;
  }
  pos_ = 0;
  end_ = n;
}

std::size_t InputStream::fill(std::size_t n) {
  if (end_ - pos_ >= n || eof_) return end_ - pos_;
  // Move the unread tail to the front, grow if one request needs more than the buffer.
  consumed_ += pos_;
  std::memmove(buffer_.data(), buffer_.data() + pos_, end_ - pos_);
  end_ -= pos_;
  pos_ = 0;
  if (buffer_.size() < n) buffer_.resize(std::max(n, buffer_.size() * 2));
  while (end_ < n && !eof_) {
    std::size_t got = source_->read(buffer_.data() + end_, buffer_.size() - end_);
    if (got == 0) eof_ = true;
    end_ += got;
  }
  return end_ - pos_;
}

bool InputStream::next_line(std::string_view& line) {
  std::size_t search_from = 0;
  for (;;) {
    const char* start = buffer_.data() + pos_;
    std::size_t avail = end_ - pos_;
    const void* nl = avail > search_from ? std::memchr(start + search_from, '\n', avail - search_from)
                                         : nullptr;
    if (nl) {
      std::size_t len = static_cast<const char*>(nl) - start;
      line = std::string_view(start, len);
      if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
      pos_ += len + 1;
      ++line_;
      return true;
    }
    if (eof_) {
      if (avail == 0) return false;
      line = std::string_view(start, avail);
      if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
      pos_ = end_;
      ++line_;
      return true;
    }
    search_from = avail;
    fill(std::max<std::size_t>(avail * 2, std::min(kChunk, buffer_.size() * 2)));
  }
}

void InputStream::read_exact(void* out, std::size_t n, const char* what) {
  std::uint64_t at = offset();
  if (fill(n) < n)
    fail_byte(std::string("unexpected end of file in ") + what + ": expected " +
                  std::to_string(n) + " more bytes, found " + std::to_string(available()),
              at);
  std::memcpy(out, data(), n);
  pos_ += n;
}

void InputStream::fail_line(const std::string& reason) const {
  throw ParseError({name_, line_, {}, {}}, reason);
}

void InputStream::fail_byte(const std::string& reason, std::uint64_t byte) const {
  throw ParseError({name_, {}, {}, byte}, reason);
}

bool parse_float(std::string_view token, double& value) {
  if (token.empty()) return false;
  const char* begin = token.data();
  const char* end = begin + token.size();
  if (*begin == '+') ++begin;  // from_chars refuses a leading '+'
  auto [ptr, ec] = std::from_chars(begin, end, value);
  if (ec == std::errc::result_out_of_range) {
    value = HUGE_VAL;  // caught as non-finite by the caller
    return ptr == end;
  }
  return ec == std::errc() && ptr == end;
}

bool parse_int(std::string_view token, std::int64_t& value) {
  if (token.empty()) return false;
  const char* begin = token.data();
  const char* end = begin + token.size();
  if (*begin == '+') ++begin;
  auto [ptr, ec] = std::from_chars(begin, end, value);
  return ec == std::errc() && ptr == end;
}

std::string_view next_token(std::string_view& line) {
  std::size_t i = 0;
  while (i < line.size() && (line[i] == ' ' || line[i] == '\t' || line[i] == '\r' ||
                             line[i] == '\f' || line[i] == '\v'))
    ++i;
  std::size_t j = i;
  while (j < line.size() && !(line[j] == ' ' || line[j] == '\t' || line[j] == '\r' ||
                              line[j] == '\f' || line[j] == '\v'))
    ++j;
  std::string_view token = line.substr(i, j - i);
  line.remove_prefix(j);
  return token;
}

}  // namespace meshflow::mesh
