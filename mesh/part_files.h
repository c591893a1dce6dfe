#pragma once
// One part of a partitioned mesh (DESIGN §9), as written by the partitioner and read by the
// workers and the merge: its vertices with their global index (ascending), a flag for the
// vertices it shares with other parts, its triangles in local ids, and optionally one quadric
// per vertex (a simplified part carries them to the merge).
//
// Binary, little-endian: "MFPART1\n", u64 #V, u64 #T, u8 has_quadrics, then per vertex
// u64 global id, 3 x f32 position, u8 shared, [11 x f64 quadric]; then per triangle 3 x u32.
// A part's boundary is its shared flags.

#include <array>
#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "mesh/mesh.h"

namespace meshflow::mesh {

struct PartFile {
  std::vector<std::uint64_t> global_ids;
  std::vector<Point> positions;
  std::vector<std::uint8_t> shared;
  std::vector<Triangle> triangles;
  std::vector<std::array<double, 11>> quadrics;  // empty, or one per vertex
};

std::vector<std::uint8_t> encode_part(const PartFile& part);
// \throws ParseError naming `name` and the byte offset on any malformed content.
PartFile decode_part(std::span<const std::uint8_t> bytes, const std::string& name);

void write_part(const PartFile& part, const std::string& path);
PartFile read_part(const std::string& path);

// The index of a parts folder (partition.txt), text:
//   parts N / diagonal X (17 significant digits) / one "neighbours P Q..." line per part.
struct PartsIndex {
  std::size_t parts = 0;
  double diagonal = 0;                                  // of the whole input's bounding box
  std::vector<std::vector<std::uint32_t>> adjacency;    // parts sharing a vertex, ascending
};
std::string encode_parts_index(const PartsIndex& index);
// \throws ParseError naming `name` and the line on any malformed content.
PartsIndex decode_parts_index(std::string_view text, const std::string& name);

}  // namespace meshflow::mesh
