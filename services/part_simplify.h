#pragma once
// The per-part step of DESIGN §9, run by local workers and by nodes (POST /parts/simplify):
// one part file in, its simplified part file out, with one quadric per surviving vertex
// exported, so that the coordinator's seam pass (parallel/merge.h) starts from the error
// already spent. Without PartSeams every shared vertex is held fixed (never moved nor
// removed). With them, the thesis's Rem scheme (ch. 9): the part first replays what its
// already simplified neighbours removed on their common boundaries (their Rem files), keeps
// the vertices shared by 3+ parts or with a simplified neighbour, and may remove a vertex
// shared with one unsimplified neighbour R by a half-edge collapse along the R boundary,
// logged in the Rem file for R.

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "mesh/part_files.h"

namespace meshflow::services {

struct PartStats {
  std::size_t vertices_in = 0, triangles_in = 0, vertices_out = 0, triangles_out = 0, shared = 0;
  std::size_t replayed = 0;      // shared vertices removed by replaying the neighbours' Rem files
  std::size_t seam_removed = 0;  // shared vertices removed here by half-edge collapses (logged)
  double max_rms_error = 0, seconds = 0;
  std::string to_json() const;
};

struct PartSeams {
  std::uint32_t part = 0;                 // this part's number
  std::vector<mesh::RemFile> incoming;    // from the simplified neighbours (to == part)
  std::vector<std::uint32_t> unsimplified;  // neighbours still to come: one Rem file each out
  // Optional, in the order of `unsimplified`: their sides of the seams (mesh::seam_sides, as
  // partitioned), so that a collapse on a seam is checked on the neighbour's side too (link
  // condition, no flipped triangle); a whole part file also does.
  std::vector<mesh::PartFile> unsimplified_parts;
};

// \throws InvalidInput when max_error_abs <= 0, or when a Rem file does not fit the part.
// With seams, `outgoing` receives one Rem file per seams->unsimplified neighbour, in that order.
mesh::PartFile simplify_part(const mesh::PartFile& part, double max_error_abs, PartStats* stats = nullptr,
                             const PartSeams* seams = nullptr, std::vector<mesh::RemFile>* outgoing = nullptr);

// Reads `in` (ParseError naming it on damage), writes `out` through out.tmp and a rename.
PartStats simplify_part_file(const std::string& in, const std::string& out, double max_error_abs);

}  // namespace meshflow::services
