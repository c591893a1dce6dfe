#pragma once
// Simplification in parts (Cabiddu, ch. 9, reshaped): the input is cut into BSP parts, every
// part is simplified on its own by a pool of workers with the vertices it shares with other
// parts held fixed, the parts are merged by global vertex id (the quadrics of shared vertices
// added up, so no error is forgotten), and a last pass over the merged mesh simplifies the
// seams with the accumulated quadrics. The seams match by construction: a shared vertex is
// the same global vertex in every part.
//
// The steps talk through part files (mesh/part_files.h) in a parts directory: part-<i>.mfp
// from the partition, part-<i>.simplified.mfp (with quadrics) from the workers.
// Not yet as the issue asks: the partition holds the input in memory, the workers are local
// processes or threads (no nodes), and the seam pass runs on the whole merged mesh in memory.

#include <cstddef>
#include <functional>
#include <string>

#include "mesh/mesh.h"
#include "parallel/independent_sets.h"

namespace meshflow::parallel {

struct DistributedParams {
  double max_error = 0;               // absolute distance
  std::size_t vertices_per_part = 1000000;
  unsigned workers = 2;
  std::string parts_dir;
  // When set, each part is simplified by a process `worker_executable part-simplify DIR P
  // --max-error-abs X` (meshflow itself); otherwise by a thread of this process.
  std::string worker_executable;
  std::function<void(const std::string& step, double fraction)> progress;
};

struct DistributedReport {
  std::size_t parts = 0, samples = 0, seam_vertices = 0;
  std::size_t merged_vertices = 0, output_vertices = 0;
  double partition_seconds = 0, parts_seconds = 0, merge_seconds = 0, seams_seconds = 0;
  PartGraph adjacency;                                      // from the partition
  std::vector<std::vector<std::uint32_t>> independent_sets;  // of at most `workers` parts: recorded for the
                                                            // node dispatch; fixed seams make every part independent
  std::string to_json() const;
};

// Writes part-<i>.mfp into `dir`; returns the number of parts.
std::size_t partition_to_files(const mesh::Mesh& input, std::size_t vertices_per_part, const std::string& dir,
                               DistributedReport& report);
// One part: part-<p>.mfp -> part-<p>.simplified.mfp, its shared vertices fixed.
void simplify_one_part(const std::string& dir, std::size_t p, double max_error);
// part-<i>.mfp -> part-<i>.simplified.mfp, `params.workers` at a time, shared vertices fixed.
void simplify_part_files(const std::string& dir, std::size_t parts, const DistributedParams& params,
                         DistributedReport& report);
// The simplified parts merged by global id, then the seams simplified.
mesh::Mesh merge_part_files(const std::string& dir, std::size_t parts, const DistributedParams& params,
                            DistributedReport& report);
// The three steps in a row, through params.parts_dir.
mesh::Mesh simplify_distributed(const mesh::Mesh& input, const DistributedParams& params, DistributedReport& report);

}  // namespace meshflow::parallel
