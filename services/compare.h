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
  std::string to_json() const;
};

struct CompareParams {
  std::size_t min_samples = 100'000;
  std::size_t max_samples = 2'000'000;
  double samples_per_triangle = 10;
  std::uint64_t seed = 1;
};

CompareResult compare(const mesh::Mesh& a, const mesh::Mesh& b, const CompareParams& params = {});

}  // namespace meshflow::services
