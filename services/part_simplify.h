#pragma once
// The per-part step of DESIGN §9, run by local workers and by nodes (POST /parts/simplify):
// one part file in, its simplified part file out, with the vertices it shares with other parts
// held fixed (never moved nor removed) and one quadric per surviving vertex exported, so that
// the coordinator's seam pass (parallel/merge.h) starts from the error already spent.

#include <cstddef>
#include <string>

#include "mesh/part_files.h"

namespace meshflow::services {

struct PartStats {
  std::size_t vertices_in = 0, triangles_in = 0, vertices_out = 0, triangles_out = 0, shared = 0;
  double max_rms_error = 0, seconds = 0;
  std::string to_json() const;
};

// \throws InvalidInput when max_error_abs <= 0.
mesh::PartFile simplify_part(const mesh::PartFile& part, double max_error_abs, PartStats* stats = nullptr);

// Reads `in` (ParseError naming it on damage), writes `out` through out.tmp and a rename.
PartStats simplify_part_file(const std::string& in, const std::string& out, double max_error_abs);

}  // namespace meshflow::services
