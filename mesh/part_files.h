#pragma once
// One part of a partitioned mesh (DESIGN §9), as written by the partitioner and read by the
// workers and the merge: its vertices with their global index (ascending), for each vertex the
// other part that uses it (its partner), its triangles in local ids, and optionally one quadric
// per vertex (a simplified part carries them to the merge).
//
// Binary, little-endian: "MFPART2\n", u64 #V, u64 #T, u8 has_quadrics, then per vertex
// u64 global id, 3 x f32 position, u32 partner, [11 x f64 quadric]; then per triangle 3 x u32.
// partner: the one other part using the vertex, kNotShared or kSharedBy3. A part's boundary
// is its shared vertices.

#include <array>
#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "mesh/mesh.h"

namespace meshflow::mesh {

constexpr std::uint32_t kNotShared = 0xFFFFFFFFu;  // used by this part only
constexpr std::uint32_t kSharedBy3 = 0xFFFFFFFEu;  // used by three or more parts
constexpr std::uint32_t kMaxParts = 1u << 24;       // partners are below this

struct PartFile {
  std::vector<std::uint64_t> global_ids;
  std::vector<Point> positions;
  std::vector<std::uint32_t> partner;  // per vertex: a part number, kNotShared or kSharedBy3
  bool shared(std::size_t v) const { return partner[v] != kNotShared; }
  std::vector<Triangle> triangles;
  std::vector<std::array<double, 11>> quadrics;  // empty, or one per vertex
};

// Each seam of `part` seen from this side: for each part q that shares some vertex with this part
// alone (a partner), this part's triangles with a corner shared with q, their vertices numbered
// in this part's order (global ids still ascending). The partitioner writes them beside the
// parts; the part q checks its half-edge collapses along the seam against them.
std::vector<std::pair<std::uint32_t, PartFile>> seam_sides(const PartFile& part);

std::vector<std::uint8_t> encode_part(const PartFile& part);
// \throws ParseError naming `name` and the byte offset on any malformed content.
PartFile decode_part(std::span<const std::uint8_t> bytes, const std::string& name);

void write_part(const PartFile& part, const std::string& path);
PartFile read_part(const std::string& path);

// A Rem file (DESIGN §9, the thesis's ch. 9): what part `from` removed on its boundary with
// part `to`, as vertex merges (removed global id -> kept global id) in collapse order. `to`
// replays them before simplifying, so that their common boundary is the same on both sides.
//
// Binary, little-endian: "MFREM01\n", u32 from, u32 to, u64 #merges, then per merge u64
// removed, u64 kept. A vertex is removed at most once and never kept after its removal.
struct RemFile {
  std::uint32_t from = 0, to = 0;
  std::vector<std::pair<std::uint64_t, std::uint64_t>> merges;  // (removed, kept)
};
std::vector<std::uint8_t> encode_rem(const RemFile& rem);
// \throws ParseError naming `name` and the byte offset on any malformed content.
RemFile decode_rem(std::span<const std::uint8_t> bytes, const std::string& name);
void write_rem(const RemFile& rem, const std::string& path);  // through path.tmp and a rename
RemFile read_rem(const std::string& path);

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
