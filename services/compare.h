#pragma once
// Metro-style comparison of two surfaces (Cignoni et al. 1998): uniform samples on each surface,
// the distance of each to the other surface by an AABB tree; mean and max in both directions,
// as a percentage of A's bounding-box diagonal.

#include <cstdint>
#include <string>

#include "mesh/mesh.h"

namespace meshflow::services {

struct CompareResult {
  double mean_ab = 0, mean_ba = 0, max_ab = 0, max_ba = 0;  // % of A's diagonal
  std::size_t samples_a = 0, samples_b = 0;
  bool one_way = false;  // compare_one_way(): the B->A fields are not measured
  std::string to_json() const;
};

struct CompareParams {
  std::size_t min_samples = 100'000;
  std::size_t max_samples = 2'000'000;
  double samples_per_triangle = 10;
  std::uint64_t seed = 1;
};

CompareResult compare(const mesh::Mesh& a, const mesh::Mesh& b, const CompareParams& params = {});

// One way, for an A too large to load (DESIGN §9's figures): A is streamed from its file and
// its vertices are the samples (about params.max_samples of them, chosen by a hash of their
// index; all of them when the file does not declare its count), each measured to B's surface.
// Fills mean_ab, max_ab and samples_a, in % of A's diagonal. \throws ParseError, IoError.
CompareResult compare_one_way(const std::string& a_path, const mesh::Mesh& b, const CompareParams& params = {});

}  // namespace meshflow::services
