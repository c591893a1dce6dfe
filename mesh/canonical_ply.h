#pragma once
// The canonical serialization of DESIGN §6: binary little-endian PLY with exactly the header
//   ply / format binary_little_endian 1.0 / element vertex N / property float x|y|z /
//   element face M / property list uchar int vertex_indices / end_header
// (no comments). Every mesh hash is the SHA-256 of these bytes, so producer and receiver
// agree bit for bit.

#include <cstdint>
#include <ostream>
#include <string>
#include <vector>

#include "mesh/mesh.h"

namespace meshflow::mesh {

// The header text for the given counts (ends with "end_header\n").
std::string canonical_ply_header(std::uint64_t vertex_count, std::uint64_t triangle_count);

// Size in bytes of the canonical serialization: header + 12 per vertex + 13 per triangle.
std::uint64_t canonical_ply_size(std::uint64_t vertex_count, std::uint64_t triangle_count);

// Writes the canonical bytes to a stream. \throws IoError when the stream fails.
void write_canonical_ply(const Mesh& mesh, std::ostream& out);

// The canonical bytes in memory (tests, small meshes).
std::vector<std::uint8_t> canonical_ply_bytes(const Mesh& mesh);

// Lowercase hex SHA-256 of the canonical bytes, computed without materializing them.
std::string mesh_sha256(const Mesh& mesh);

// Lowercase hex SHA-256 of a byte range, and an incremental hasher for streams.
std::string sha256_hex(const void* data, std::size_t size);
class Sha256 {
 public:
  Sha256();
  ~Sha256();
  Sha256(const Sha256&) = delete;
  Sha256& operator=(const Sha256&) = delete;
  void update(const void* data, std::size_t size);
  std::string hex_digest();  // finishes; the hasher is then spent

 private:
  void* ctx_;
};

}  // namespace meshflow::mesh
