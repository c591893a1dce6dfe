#pragma once
// Simplification in parts (Cabiddu, ch. 9, reshaped): the input is cut into BSP parts, every
// part is simplified on its own by a pool of workers with the vertices it shares with other
// parts held fixed, the parts are merged by global vertex id (the quadrics of shared vertices
// added up, so no error is forgotten), and a last pass over the merged mesh simplifies the
// seams with the accumulated quadrics. The seams match by construction: a shared vertex is
// the same global vertex in every part.
//
// Not yet as the issue asks: the input is held in memory, the workers are threads of this
// process (no part files, no nodes), and the seam pass runs on the whole merged mesh.

#include <cstddef>
#include <functional>
#include <string>

#include "mesh/mesh.h"

namespace meshflow::parallel {

struct DistributedParams {
  double max_error = 0;               // absolute distance
  std::size_t vertices_per_part = 1000000;
  unsigned workers = 2;
  std::function<void(const std::string& step, double fraction)> progress;
};

struct DistributedReport {
  std::size_t parts = 0, samples = 0, seam_vertices = 0;
  std::size_t merged_vertices = 0, output_vertices = 0;
  double partition_seconds = 0, parts_seconds = 0, merge_seconds = 0, seams_seconds = 0;
  std::string to_json() const;
};

mesh::Mesh simplify_distributed(const mesh::Mesh& input, const DistributedParams& params, DistributedReport& report);

}  // namespace meshflow::parallel
