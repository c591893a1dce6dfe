#pragma once
// Out of core (issue 7): any mesh file the readers accept, copied to the canonical binary PLY
// of DESIGN §6 without the mesh in memory; and a file's vertex count and bounding box,
// measured without loading it. The hub canonicalises a job's input with these.
//
// The copy streams the input (stream_mesh()) into two scratch files beside the output,
// `OUT.vertices.tmp` (12 bytes a vertex) and `OUT.triangles.tmp` (the 13-byte canonical face
// record), because the header needs counts that only the end of the input gives (polygons
// are fan-triangulated, OBJ and STL state no counts, OBJ interleaves vertices and faces).
// Then one pass writes the header, the vertices and the triangles to `OUT.tmp`, hashing them,
// and renames it to OUT. The scratch files are removed whatever happens.
//
// read_mesh() is stream_mesh() into a Mesh and does nothing afterwards: every format's reader
// (STL's welding of equal positions included) works in the stream, so the copy gives exactly
// write_mesh(read_mesh(IN), OUT) for every format and no format falls back to read_mesh().
//
// Memory: bounded buffers (the reader's 4 MiB, batches of 64k elements, `buffer_bytes`, the
// compressor's state), a few MB whatever the input's size. One exception is inherent to the
// format: the STL reader welds with a map of the distinct positions seen so far (about 65 bytes
// a vertex at its peak); read_mesh() holds that map and the whole mesh besides.
// Disk: the scratch files hold about the canonical size while the output is being written.

#include <cstddef>
#include <cstdint>
#include <string>

#include "mesh/mesh.h"
#include "mesh/mesh_io.h"

namespace meshflow::mesh {

struct CanonicalCopyParams {
  // Size of each scratch file's write buffer and of the chunks of the final pass.
  std::size_t buffer_bytes = std::size_t{1} << 20;
};

struct CanonicalCopy {
  std::uint64_t vertices = 0;
  std::uint64_t triangles = 0;
  Box box;               // of all vertices, referenced or not: bounding_box(read_mesh(IN))
  double diagonal = 0;   // box.diagonal()
  std::string sha256;    // of the canonical (uncompressed) bytes: mesh_sha256(read_mesh(IN))
  std::uint64_t canonical_bytes = 0;  // canonical_ply_size(vertices, triangles)
  ReadInfo info;         // what the reader saw
};

// Whether `path` names canonical PLY output: .ply, .ply.gz or .ply.zst (any case).
bool is_canonical_ply_path(const std::string& path);

// Copies the mesh at `in_path` (any format and compression the readers take) to `out_path`,
// which must end in .ply, .ply.gz or .ply.zst; the bytes are those of
// write_mesh(read_mesh(in_path), out_path). Written to `out_path.tmp`, then renamed; on any
// error neither the output nor a scratch file is left (an older OUT stays as it was).
// \throws InvalidInput when `out_path` is not a .ply path (before reading anything),
//         ParseError from the reader (naming the file and the line or byte), IoError.
CanonicalCopy copy_canonical_ply(const std::string& in_path, const std::string& out_path,
                                 const CanonicalCopyParams& params = {});

struct MeshExtent {
  std::uint64_t vertices = 0;
  Box box;  // of all vertices: bounding_box(read_mesh(path))
  double diagonal() const { return box.diagonal(); }
};

// The vertex count and bounding box of the mesh at `path`, streamed (the reader skips face
// data where the format lets it); memory is the reader's buffers (STL: its welding map).
// Meant for files already read once (the hub's canonical input): faces are checked less than
// by read_mesh(), so a damaged face section may go unnoticed. \throws ParseError, IoError.
MeshExtent measure_extent(const std::string& path);

}  // namespace meshflow::mesh
