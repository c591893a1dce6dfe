#pragma once
// Reading and writing meshes: PLY (ascii, binary LE/BE), OFF (COFF/NOFF...), OBJ, STL
// (ascii/binary). Input may be gzip- or zstd-compressed; format and compression are
// detected from the content, the extension is only a hint. Readers are safe to use on
// untrusted input: they throw ParseError naming the file and the line (text) or byte offset
// (binary, counted in the decompressed content), never crash, never pre-allocate from a
// header's counts beyond what the input can hold.

#include <cstdint>
#include <span>
#include <string>

#include "mesh/mesh.h"

namespace meshflow::mesh {

enum class Format { Ply, Off, Obj, Stl };
enum class Compression { None, Gzip, Zstd };
const char* to_string(Format format);
const char* to_string(Compression compression);

// What a reader saw beyond the mesh itself.
struct ReadInfo {
  Format format = Format::Ply;
  Compression compression = Compression::None;
  bool is_binary = false;
  std::uint64_t faces_read = 0;       // faces as stored (a polygon counts once)
  std::uint64_t polygons = 0;         // faces with more than 3 vertices (fan-triangulated)
  std::uint64_t raw_vertices = 0;     // STL: corners before welding; others: vertices read
};

// Receives a mesh in file order without the file being loaded (DESIGN §9 builds on it).
// Triangle indices are 0-based global vertex ids, already validated against the vertices
// the file declares; polygons arrive fan-triangulated. OBJ may interleave the two calls.
class MeshSink {
 public:
  virtual ~MeshSink() = default;
  // Declared counts when the format states them up front (PLY, OFF), else unknown (-1).
  virtual void begin(Format format, std::int64_t vertex_count, std::int64_t face_count) {}
  virtual void vertices(std::span<const Point> batch) = 0;
  virtual void triangles(std::span<const Triangle> batch) = 0;
  virtual void end() {}
  // A sink that only needs vertices (bounding box, sampling) says so; readers then skip
  // face data when the format lets them.
  virtual bool wants_triangles() const { return true; }
};

// Streams the mesh at `path` into `sink`. \throws ParseError, IoError.
ReadInfo stream_mesh(const std::string& path, MeshSink& sink);

// Reads the whole mesh. \throws ParseError, IoError.
Mesh read_mesh(const std::string& path, ReadInfo* info = nullptr);

// Reads from bytes in memory (fuzzing, uploads); `name` is used in error messages.
Mesh read_mesh_from_memory(std::span<const std::uint8_t> bytes, const std::string& name,
                           ReadInfo* info = nullptr);

// Writes by the output's extension: .ply (canonical binary PLY of DESIGN §6), .off, .obj,
// .stl (binary); a trailing .gz or .zst compresses. Written to `<path>.tmp`, then renamed.
// \throws InvalidInput for an unknown extension, IoError when writing fails.
void write_mesh(const Mesh& mesh, const std::string& path);

// A whole file's bytes, in one read. \throws IoError.
std::vector<std::uint8_t> read_file_bytes(const std::string& path);
// Written to `<path>.tmp`, then renamed. \throws IoError.
void write_file_bytes(const std::string& path, std::span<const std::uint8_t> bytes);

}  // namespace meshflow::mesh
