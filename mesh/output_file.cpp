#include "mesh/output_file.h"

#include <algorithm>
#include <cstring>
#include <filesystem>

#include "mesh/errors.h"

namespace meshflow::mesh {

std::string lower_extension(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
  return ext;
}

std::pair<std::string, Compression> strip_compression(const std::string& path) {
  std::string ext = lower_extension(path);
  if (ext == ".gz") return {path.substr(0, path.size() - 3), Compression::Gzip};
  if (ext == ".zst") return {path.substr(0, path.size() - 4), Compression::Zstd};
  return {path, Compression::None};
}

OutputFile::OutputFile(std::string path, Compression compression)
    : path_(std::move(path)), tmp_(path_ + ".tmp"), compression_(compression) {
  file_ = std::fopen(tmp_.c_str(), "wb");
  if (!file_) throw IoError(path_ + ": cannot create " + tmp_);
  if (compression_ == Compression::Gzip) {
    std::memset(&z_, 0, sizeof z_);
    deflateInit2(&z_, 6, Z_DEFLATED, 16 + MAX_WBITS, 8, Z_DEFAULT_STRATEGY);
  } else if (compression_ == Compression::Zstd) {
    zstd_ = ZSTD_createCCtx();
    ZSTD_CCtx_setParameter(zstd_, ZSTD_c_compressionLevel, 3);
  }
  out_.resize(1 << 20);
}

OutputFile::~OutputFile() {
  if (file_) {
    std::fclose(file_);
    std::remove(tmp_.c_str());
  }
  if (compression_ == Compression::Gzip) deflateEnd(&z_);
  if (zstd_) ZSTD_freeCCtx(zstd_);
}

void OutputFile::write(const void* data, std::size_t size) {
  if (compression_ == Compression::None) {
    raw(data, size);
  } else if (compression_ == Compression::Gzip) {
    // zlib counts input in 32 bits: hand it over in pieces of at most 1 GiB.
    auto* bytes = static_cast<const Bytef*>(data);
    while (size > 0) {
      std::size_t piece = std::min<std::size_t>(size, std::size_t{1} << 30);
      z_.next_in = const_cast<Bytef*>(bytes);
      z_.avail_in = static_cast<uInt>(piece);
      deflate_all(Z_NO_FLUSH);
      bytes += piece;
      size -= piece;
    }
  } else {
    ZSTD_inBuffer in{data, size, 0};
    while (in.pos < in.size) zstd_step(in, ZSTD_e_continue);
  }
}

void OutputFile::commit() {
  if (compression_ == Compression::Gzip) {
    z_.avail_in = 0;
    deflate_all(Z_FINISH);
  } else if (compression_ == Compression::Zstd) {
    ZSTD_inBuffer in{nullptr, 0, 0};
    while (zstd_step(in, ZSTD_e_end) != 0) {
    }
  }
  bool ok = std::fflush(file_) == 0 && !std::ferror(file_);
  ok = std::fclose(file_) == 0 && ok;
  file_ = nullptr;
  if (!ok) {
    std::remove(tmp_.c_str());
    throw IoError(path_ + ": write failed (disk full?)");
  }
  std::filesystem::rename(tmp_, path_);
}

void OutputFile::raw(const void* data, std::size_t size) {
  if (std::fwrite(data, 1, size, file_) != size) throw IoError(path_ + ": write failed (disk full?)");
}

void OutputFile::deflate_all(int flush) {
  do {
    z_.next_out = reinterpret_cast<Bytef*>(out_.data());
    z_.avail_out = static_cast<uInt>(out_.size());
    deflate(&z_, flush);
    raw(out_.data(), out_.size() - z_.avail_out);
  } while (z_.avail_out == 0);
}

std::size_t OutputFile::zstd_step(ZSTD_inBuffer& in, ZSTD_EndDirective mode) {
  ZSTD_outBuffer out{out_.data(), out_.size(), 0};
  std::size_t remaining = ZSTD_compressStream2(zstd_, &out, &in, mode);
  if (ZSTD_isError(remaining)) throw IoError(path_ + ": zstd compression failed");
  raw(out_.data(), out.pos);
  return remaining;
}

}  // namespace meshflow::mesh
