#include "mesh/canonical_copy.h"

#include <algorithm>
#include <cstdio>
#include <cstring>
#include <utility>
#include <vector>

#include "mesh/canonical_ply.h"
#include "mesh/errors.h"
#include "mesh/output_file.h"

namespace meshflow::mesh {
namespace {

constexpr std::size_t kVertexBytes = 12;
constexpr std::size_t kTriangleBytes = 13;
static_assert(sizeof(Point) == kVertexBytes, "positions are packed float32 triples");

// The box of bounding_box(): min and max start at the first vertex, compared as doubles.
class BoxAccumulator {
 public:
  void add(std::span<const Point> batch) {
    for (const Point& p : batch) {
      if (count_ == 0)
        for (int k = 0; k < 3; ++k) box_.min[k] = box_.max[k] = p[k];
      for (int k = 0; k < 3; ++k) {
        box_.min[k] = std::min<double>(box_.min[k], p[k]);
        box_.max[k] = std::max<double>(box_.max[k], p[k]);
      }
      ++count_;
    }
  }
  std::uint64_t count() const { return count_; }
  const Box& box() const { return box_; }

 private:
  Box box_;
  std::uint64_t count_ = 0;
};

// A scratch file beside the output: written while the input streams, read back once, and
// removed when the object goes, whether the copy succeeded or not.
class ScratchFile {
 public:
  ScratchFile(std::string path, std::size_t buffer_bytes) : path_(std::move(path)), buffer_(buffer_bytes) {
    file_ = std::fopen(path_.c_str(), "w+b");
    if (!file_) throw IoError(path_ + ": cannot create a scratch file");
    std::setvbuf(file_, buffer_.data(), _IOFBF, buffer_.size());
  }
  ~ScratchFile() {
    if (file_) std::fclose(file_);
    std::remove(path_.c_str());
  }
  ScratchFile(const ScratchFile&) = delete;
  ScratchFile& operator=(const ScratchFile&) = delete;

  void write(const void* data, std::size_t size) {
    if (size && std::fwrite(data, 1, size, file_) != size)
      throw IoError(path_ + ": write failed (disk full?)");
  }
  // Hands the whole content to `sink(data, size)` in chunks of `chunk.size()` bytes.
  template <typename Sink>
  void replay(std::vector<char>& chunk, Sink&& sink) {
    if (std::fflush(file_) != 0 || std::fseek(file_, 0, SEEK_SET) != 0)
      throw IoError(path_ + ": write failed (disk full?)");
    for (;;) {
      std::size_t n = std::fread(chunk.data(), 1, chunk.size(), file_);
      if (n > 0) sink(chunk.data(), n);
      if (n < chunk.size()) break;
    }
    if (std::ferror(file_)) throw IoError(path_ + ": cannot read the scratch file back");
  }

 private:
  std::string path_;
  std::vector<char> buffer_;  // the FILE's buffer (closed in the destructor's body, before this goes)
  std::FILE* file_ = nullptr;
};

// Vertices and triangles, in file order, to the two scratch files (OBJ may interleave them).
class ScratchSink : public MeshSink {
 public:
  ScratchSink(ScratchFile& vertices, ScratchFile& triangles) : vertices_(vertices), triangles_(triangles) {}
  void vertices(std::span<const Point> batch) override {
    box_.add(batch);
    vertices_.write(batch.data(), batch.size() * kVertexBytes);
  }
  void triangles(std::span<const Triangle> batch) override {
    records_.resize(batch.size() * kTriangleBytes);
    char* out = records_.data();
    for (const Triangle& t : batch) {
      out[0] = 3;
      std::memcpy(out + 1, t.data(), 12);
      out += kTriangleBytes;
    }
    triangles_.write(records_.data(), records_.size());
    triangle_count_ += batch.size();
  }
  const BoxAccumulator& box() const { return box_; }
  std::uint64_t triangle_count() const { return triangle_count_; }

 private:
  ScratchFile& vertices_;
  ScratchFile& triangles_;
  BoxAccumulator box_;
  std::uint64_t triangle_count_ = 0;
  std::vector<char> records_;  // one batch's canonical face records
};

class ExtentSink : public MeshSink {
 public:
  void vertices(std::span<const Point> batch) override { box.add(batch); }
  void triangles(std::span<const Triangle>) override {}
  bool wants_triangles() const override { return false; }
  BoxAccumulator box;
};

}  // namespace

bool is_canonical_ply_path(const std::string& path) {
  return lower_extension(strip_compression(path).first) == ".ply";
}

CanonicalCopy copy_canonical_ply(const std::string& in_path, const std::string& out_path,
                                 const CanonicalCopyParams& params) {
  auto [base, compression] = strip_compression(out_path);
  if (lower_extension(base) != ".ply")
    throw InvalidInput(out_path + ": the canonical copy writes .ply, .ply.gz or .ply.zst, not '" +
                       lower_extension(base) + "'");
  std::size_t buffer_bytes = std::max<std::size_t>(params.buffer_bytes, 4096);

  CanonicalCopy result;
  ScratchFile vertices(out_path + ".vertices.tmp", buffer_bytes);
  ScratchFile triangles(out_path + ".triangles.tmp", buffer_bytes);
  ScratchSink sink(vertices, triangles);
  result.info = stream_mesh(in_path, sink);
  result.vertices = sink.box().count();
  result.triangles = sink.triangle_count();
  result.box = sink.box().box();
  result.diagonal = result.box.diagonal();

  // Header, vertices, triangles: written and hashed in one pass.
  OutputFile out(out_path, compression);
  Sha256 hasher;
  auto emit = [&](const void* data, std::size_t size) {
    hasher.update(data, size);
    out.write(data, size);
    result.canonical_bytes += size;
  };
  std::string header = canonical_ply_header(result.vertices, result.triangles);
  emit(header.data(), header.size());
  std::vector<char> chunk(buffer_bytes);
  vertices.replay(chunk, emit);
  triangles.replay(chunk, emit);
  // A scratch file that lost bytes on the way would give a file whose header lies.
  if (result.canonical_bytes != canonical_ply_size(result.vertices, result.triangles))
    throw IoError(out_path + ": the scratch files gave " + std::to_string(result.canonical_bytes) +
                  " bytes, expected " + std::to_string(canonical_ply_size(result.vertices, result.triangles)));
  out.commit();
  result.sha256 = hasher.hex_digest();
  return result;
}

MeshExtent measure_extent(const std::string& path) {
  ExtentSink sink;
  stream_mesh(path, sink);
  return {sink.box.count(), sink.box.box()};
}

}  // namespace meshflow::mesh
