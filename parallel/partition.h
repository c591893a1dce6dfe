#pragma once
// The out-of-core partition of DESIGN §9 (Cabiddu, ch. 8), from the input file with the
// streaming reader, never the whole mesh in memory:
//   pass 1: bounding box and a 1:1000 vertex sample; the BSP on the sample;
//   pass 2: each vertex to its cell's vertex file (global id, position), each triangle to a cell
//           by the thesis's three cases (all in one cell: that cell; two in one cell: that cell;
//           three cells: the one with the lexicographically smallest centre), a request for each
//           foreign corner written to the file of the corner's own cell;
//   join:   per cell, its vertex file answers the requests made to it (a merge join by global
//           id): each requesting cell gets a copy of the vertex, flagged shared when two or more
//           parts use it; the part adjacency graph comes out of the same join;
//   parts:  per cell, part-<p>.mfp (mesh/part_files.h), cells without triangles dropped.
// Memory: during pass 2 the vertices' cell ids (so that a triangle finds its corners' cells) go
// to a scratch file read back in windows (parallel/cell_ids.h, at most 256 MB held), then one part
// at a time. Disk: the scratch files are deleted as the parts are written.

#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>

#include "parallel/independent_sets.h"

namespace meshflow::parallel {

struct PartitionInfo {
  std::size_t parts = 0, samples = 0;
  std::uint64_t input_vertices = 0, input_triangles = 0;
  std::uint64_t shared_vertices = 0;      // used by triangles of two or more parts
  std::uint64_t shared_by_3_or_more = 0;
  double diagonal = 0;                    // of the input's bounding box
  PartGraph adjacency;                    // parts sharing a vertex
  double seconds = 0;
};

// Writes DIR/part-<p>.mfp, their seam sides DIR/seam-<p>-<q>.mfp and DIR/partition.txt. \throws ParseError, IoError, InvalidInput.
PartitionInfo partition_file(const std::string& input, std::size_t vertices_per_part, const std::string& dir,
                             const std::function<void(double)>& progress = {});

// DIR/partition.txt: parts, diagonal and the adjacency graph.
void write_partition_info(const std::string& dir, const PartitionInfo& info);
// \throws InvalidInput naming the file when it is missing or malformed.
PartitionInfo read_partition_info(const std::string& dir);

std::string part_path(const std::string& dir, std::size_t p, bool simplified);
// DIR/rem-<from>-<to>.bin: what part `from` removed on its boundary with `to` (mesh::RemFile).
std::string rem_path(const std::string& dir, std::size_t from, std::size_t to);
// DIR/seam-<p>-<q>.mfp: part p's side of its seam with q as partitioned (mesh::seam_sides),
// written beside the parts; absent when p and q share no vertex with each other alone.
std::string seam_path(const std::string& dir, std::size_t p, std::size_t q);

}  // namespace meshflow::parallel
