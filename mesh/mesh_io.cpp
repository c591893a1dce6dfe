#include "mesh/mesh_io.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>

#include "mesh/canonical_ply.h"
#include "mesh/output_file.h"
#include "mesh/readers.h"

namespace meshflow::mesh {
namespace {

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
