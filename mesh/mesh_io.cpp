#include "mesh/mesh_io.h"

#include <zlib.h>
#include <zstd.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>

#include "mesh/canonical_ply.h"
#include "mesh/readers.h"

namespace meshflow::mesh {
namespace {

std::string lower_extension(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
  return ext;
}

// The path without a trailing .gz/.zst, and which compression that suffix asks for.
std::pair<std::string, Compression> strip_compression(const std::string& path) {
  std::string ext = lower_extension(path);
  if (ext == ".gz") return {path.substr(0, path.size() - 3), Compression::Gzip};
  if (ext == ".zst") return {path.substr(0, path.size() - 4), Compression::Zstd};
  return {path, Compression::None};
}

Format detect_format(InputStream& in) {
  std::size_t n = in.fill(1024);
  if (n == 0) throw ParseError({in.name(), {}, {}, 0}, "empty file: expected a PLY, OFF, OBJ or STL mesh");
  std::string_view head(in.data(), n);
  if (head.size() >= 4 && head.substr(0, 3) == "ply" && (head[3] == '\n' || head[3] == '\r'))
    return Format::Ply;
  if (in.known_size() >= 84 && n >= 84) {
    std::uint32_t count;
    std::memcpy(&count, in.data() + 80, 4);
    if (static_cast<std::uint64_t>(in.known_size()) == 84 + 50ull * count) return Format::Stl;
  }
  if (head.substr(0, 5) == "solid") return Format::Stl;
  // First token that is not a comment.
  std::string_view rest = head;
  while (!rest.empty()) {
    std::string_view line = rest.substr(0, rest.find('\n'));
    rest.remove_prefix(std::min(rest.size(), line.size() + 1));
    std::string_view token = next_token(line);
    if (token.empty() || token[0] == '#') continue;
    if (token.size() >= 3 && token.substr(token.size() - 3) == "OFF") return Format::Off;
    static const std::string_view obj_keywords[] = {"v", "vt", "vn", "vp", "f", "o", "g",
                                                    "s", "mtllib", "usemtl", "l", "p"};
    for (auto k : obj_keywords)
      if (token == k) return Format::Obj;
    break;
  }
  std::string ext = lower_extension(strip_compression(in.name()).first);
  if (ext == ".stl") return Format::Stl;  // a binary STL with a lying count: its reader says so
  if (ext == ".off") return Format::Off;
  if (ext == ".obj") return Format::Obj;
  if (ext == ".ply") return Format::Ply;
  throw ParseError({in.name(), {}, {}, 0},
                   "unrecognised content: expected a PLY, OFF, OBJ or STL mesh");
}

ReadInfo stream_from(InputStream& in, MeshSink& sink) {
  Format format = detect_format(in);
  ReadInfo info;
  switch (format) {
    case Format::Ply: info = read_ply(in, sink); break;
    case Format::Off: info = read_off(in, sink); break;
    case Format::Obj: info = read_obj(in, sink); break;
    case Format::Stl: info = read_stl(in, sink); break;
  }
  info.compression = in.compression();
  return info;
}

class MeshBuilder : public MeshSink {
 public:
  void begin(Format, std::int64_t vertex_count, std::int64_t face_count) override {
    if (vertex_count > 0) mesh.positions.reserve(static_cast<std::size_t>(vertex_count));
    if (face_count > 0) mesh.triangles.reserve(static_cast<std::size_t>(face_count));
  }
  void vertices(std::span<const Point> batch) override {
    mesh.positions.insert(mesh.positions.end(), batch.begin(), batch.end());
  }
  void triangles(std::span<const Triangle> batch) override {
    mesh.triangles.insert(mesh.triangles.end(), batch.begin(), batch.end());
  }
  Mesh mesh;
};

// Output with optional gzip or zstd compression, written to PATH.tmp and renamed by commit().
class OutputFile {
 public:
  OutputFile(std::string path, Compression compression)
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
  ~OutputFile() {
    if (file_) {
      std::fclose(file_);
      std::remove(tmp_.c_str());
    }
    if (compression_ == Compression::Gzip) deflateEnd(&z_);
    if (zstd_) ZSTD_freeCCtx(zstd_);
  }
  void write(const void* data, std::size_t size) {
    if (compression_ == Compression::None) {
      raw(data, size);
    } else if (compression_ == Compression::Gzip) {
      z_.next_in = static_cast<Bytef*>(const_cast<void*>(data));
      z_.avail_in = static_cast<uInt>(size);
      deflate_all(Z_NO_FLUSH);
    } else {
      ZSTD_inBuffer in{data, size, 0};
      while (in.pos < in.size) zstd_step(in, ZSTD_e_continue);
    }
  }
  void commit() {
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
    if (!ok) throw IoError(path_ + ": write failed (disk full?)");
    std::filesystem::rename(tmp_, path_);
  }

 private:
  void raw(const void* data, std::size_t size) {
    if (std::fwrite(data, 1, size, file_) != size) throw IoError(path_ + ": write failed (disk full?)");
  }
  void deflate_all(int flush) {
    do {
      z_.next_out = reinterpret_cast<Bytef*>(out_.data());
      z_.avail_out = static_cast<uInt>(out_.size());
      deflate(&z_, flush);
      raw(out_.data(), out_.size() - z_.avail_out);
    } while (z_.avail_out == 0);
  }
  std::size_t zstd_step(ZSTD_inBuffer& in, ZSTD_EndDirective mode) {
    ZSTD_outBuffer out{out_.data(), out_.size(), 0};
    std::size_t remaining = ZSTD_compressStream2(zstd_, &out, &in, mode);
    if (ZSTD_isError(remaining)) throw IoError(path_ + ": zstd compression failed");
    raw(out_.data(), out.pos);
    return remaining;
  }
  std::string path_, tmp_;
  Compression compression_;
  std::FILE* file_ = nullptr;
  z_stream z_{};
  ZSTD_CCtx* zstd_ = nullptr;
  std::vector<char> out_;
};

// Buffered text output; floats in the shortest form that reads back to the same float32.
class TextWriter {
 public:
  explicit TextWriter(OutputFile& out) : out_(out) { buffer_.reserve(1 << 20); }
  ~TextWriter() = default;
  TextWriter& operator<<(std::string_view text) {
    buffer_.append(text);
    maybe_flush();
    return *this;
  }
  TextWriter& number(float value) {
    char tmp[32];
    auto [end, ec] = std::to_chars(tmp, tmp + sizeof tmp, value);
    buffer_.append(tmp, end);
    return *this;
  }
  TextWriter& number(std::uint64_t value) {
    char tmp[24];
    auto [end, ec] = std::to_chars(tmp, tmp + sizeof tmp, value);
    buffer_.append(tmp, end);
    return *this;
  }
  void flush() {
    out_.write(buffer_.data(), buffer_.size());
    buffer_.clear();
  }

 private:
  void maybe_flush() {
    if (buffer_.size() > (1 << 20) - 256) flush();
  }
  OutputFile& out_;
  std::string buffer_;
};

void write_off(const Mesh& mesh, OutputFile& file) {
  TextWriter w(file);
  w << "OFF\n";
  w.number(mesh.positions.size()) << " ";
  w.number(mesh.triangles.size()) << " 0\n";
  for (const Point& p : mesh.positions) {
    w.number(p[0]) << " ";
    w.number(p[1]) << " ";
    w.number(p[2]) << "\n";
  }
  for (const Triangle& t : mesh.triangles) {
    w << "3 ";
    w.number(std::uint64_t{t[0]}) << " ";
    w.number(std::uint64_t{t[1]}) << " ";
    w.number(std::uint64_t{t[2]}) << "\n";
  }
  w.flush();
}

void write_obj(const Mesh& mesh, OutputFile& file) {
  TextWriter w(file);
  w << "# meshflow\n";
  for (const Point& p : mesh.positions) {
    w << "v ";
    w.number(p[0]) << " ";
    w.number(p[1]) << " ";
    w.number(p[2]) << "\n";
  }
  for (const Triangle& t : mesh.triangles) {
    w << "f ";
    w.number(std::uint64_t{t[0]} + 1) << " ";
    w.number(std::uint64_t{t[1]} + 1) << " ";
    w.number(std::uint64_t{t[2]} + 1) << "\n";
  }
  w.flush();
}

void write_stl(const Mesh& mesh, OutputFile& file) {
  char header[80] = "binary STL written by meshflow";
  file.write(header, 80);
  if (mesh.triangles.size() > 0xFFFFFFFFull) throw InvalidInput("too many triangles for STL");
  std::uint32_t count = static_cast<std::uint32_t>(mesh.triangles.size());
  file.write(&count, 4);
  std::vector<char> buffer;
  buffer.reserve(50 * 4096);
  for (const Triangle& t : mesh.triangles) {
    const Point &a = mesh.positions[t[0]], &b = mesh.positions[t[1]], &c = mesh.positions[t[2]];
    double u[3], v[3], n[3];
    for (int k = 0; k < 3; ++k) u[k] = b[k] - a[k], v[k] = c[k] - a[k];
    n[0] = u[1] * v[2] - u[2] * v[1];
    n[1] = u[2] * v[0] - u[0] * v[2];
    n[2] = u[0] * v[1] - u[1] * v[0];
    double len = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    float normal[3] = {0, 0, 0};
    if (len > 0)
      for (int k = 0; k < 3; ++k) normal[k] = static_cast<float>(n[k] / len);
    char record[50] = {};
    std::memcpy(record, normal, 12);
    std::memcpy(record + 12, a.data(), 12);
    std::memcpy(record + 24, b.data(), 12);
    std::memcpy(record + 36, c.data(), 12);
    buffer.insert(buffer.end(), record, record + 50);
    if (buffer.size() >= 50 * 4096) {
      file.write(buffer.data(), buffer.size());
      buffer.clear();
    }
  }
  file.write(buffer.data(), buffer.size());
}

void check_writable(const Mesh& mesh) {
  for (const Triangle& t : mesh.triangles)
    for (Index v : t)
      if (v >= mesh.positions.size())
        throw InvalidInput("mesh has a triangle with vertex index " + std::to_string(v) +
                           " out of range (" + std::to_string(mesh.positions.size()) + " vertices)");
}

}  // namespace

const char* to_string(Format format) {
  switch (format) {
    case Format::Ply: return "PLY";
    case Format::Off: return "OFF";
    case Format::Obj: return "OBJ";
    case Format::Stl: return "STL";
  }
  return "?";
}

const char* to_string(Compression compression) {
  switch (compression) {
    case Compression::None: return "none";
    case Compression::Gzip: return "gzip";
    case Compression::Zstd: return "zstd";
  }
  return "?";
}

std::uint64_t plausible_count(const InputStream& in, std::uint64_t declared, std::uint64_t min_bytes) {
  constexpr std::uint64_t kUnknownSizeCap = 1ull << 24;  // grow past this as data arrives
  if (in.known_size() < 0) return std::min(declared, kUnknownSizeCap);
  return std::min(declared, static_cast<std::uint64_t>(in.known_size()) / std::max<std::uint64_t>(1, min_bytes) + 1);
}

ReadInfo stream_mesh(const std::string& path, MeshSink& sink) {
  InputStream in = InputStream::open_file(path);
  return stream_from(in, sink);
}

Mesh read_mesh(const std::string& path, ReadInfo* info) {
  MeshBuilder builder;
  ReadInfo read = stream_mesh(path, builder);
  if (info) *info = read;
  return std::move(builder.mesh);
}

Mesh read_mesh_from_memory(std::span<const std::uint8_t> bytes, const std::string& name,
                           ReadInfo* info) {
  InputStream in = InputStream::from_memory(bytes, name);
  MeshBuilder builder;
  ReadInfo read = stream_from(in, builder);
  if (info) *info = read;
  return std::move(builder.mesh);
}

void write_mesh(const Mesh& mesh, const std::string& path) {
  auto [base, compression] = strip_compression(path);
  std::string ext = lower_extension(base);
  if (ext != ".ply" && ext != ".off" && ext != ".obj" && ext != ".stl")
    throw InvalidInput(path + ": unknown output format '" + ext +
                       "' (expected .ply, .off, .obj or .stl, optionally + .gz or .zst)");
  check_writable(mesh);
  OutputFile file(path, compression);
  if (ext == ".ply") {
    std::string header = canonical_ply_header(mesh.positions.size(), mesh.triangles.size());
    file.write(header.data(), header.size());
    if (!mesh.positions.empty()) file.write(mesh.positions.data(), mesh.positions.size() * 12);
    std::vector<char> buffer;
    buffer.reserve(13 * 8192);
    for (const Triangle& t : mesh.triangles) {
      char record[13];
      record[0] = 3;
      std::memcpy(record + 1, t.data(), 12);
      buffer.insert(buffer.end(), record, record + 13);
      if (buffer.size() >= 13 * 8192) {
        file.write(buffer.data(), buffer.size());
        buffer.clear();
      }
    }
    file.write(buffer.data(), buffer.size());
  } else if (ext == ".off") {
    write_off(mesh, file);
  } else if (ext == ".obj") {
    write_obj(mesh, file);
  } else {
    write_stl(mesh, file);
  }
  file.commit();
}

std::vector<std::uint8_t> read_file_bytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary | std::ios::ate);
  if (!in) throw IoError(path + ": cannot open");
  std::vector<std::uint8_t> bytes(static_cast<std::size_t>(in.tellg()));
  in.seekg(0);
  if (!in.read(reinterpret_cast<char*>(bytes.data()), static_cast<std::streamsize>(bytes.size())))
    throw IoError(path + ": cannot read");
  return bytes;
}

void write_file_bytes(const std::string& path, std::span<const std::uint8_t> bytes) {
  std::string tmp = path + ".tmp";
  {
    std::ofstream out(tmp, std::ios::binary);
    out.write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
    if (!out) throw IoError(tmp + ": write failed");
  }
  if (std::rename(tmp.c_str(), path.c_str()) != 0) throw IoError(path + ": cannot rename " + tmp);
}

}  // namespace meshflow::mesh
