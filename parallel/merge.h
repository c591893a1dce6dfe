#pragma once
// The out-of-core merge of simplified parts (DESIGN §9), with a seam pass:
//   1. each simplified part in turn: its triangles within kSeamRings rings of a shared vertex
//      form the seam band; the band of all parts is assembled by global id (quadrics of a vertex
//      in several parts added up), a band vertex also used by the rest of its part locked;
//   2. the band is simplified with those quadrics (services/simplify.h), so the vertices the
//      parts had to keep fixed get simplified with the same error bound, cracks impossible
//      (one band, one copy of each shared vertex);
//   3. the output is written directly as canonical binary PLY (DESIGN §6): the counts are known
//      from step 1 and 2, so the header is exact; one more pass over the parts writes the
//      vertices at one file position and the triangles at another (no second copy).
// Memory: one part, the band (about the seams' size) and a map for the band's vertices.

#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>

namespace meshflow::parallel {

inline constexpr int kSeamRings = 2;

struct MergeReport {
  std::size_t band_vertices = 0, band_triangles = 0;
  std::size_t fins_removed = 0;  // pairs of band triangles on the same three vertices, facing apart
  std::uint64_t output_vertices = 0, output_triangles = 0;
  double seams_seconds = 0, merge_seconds = 0;
};

// DIR/part-<p>.simplified.mfp for p < parts -> OUT (.ply; through OUT.tmp and a rename).
// \throws ParseError naming a damaged part file, InvalidInput, IoError.
MergeReport merge_parts(const std::string& dir, std::size_t parts, double max_error_abs, const std::string& out,
                        const std::function<void(const std::string&, double)>& progress = {});

}  // namespace meshflow::parallel
