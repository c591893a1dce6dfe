#pragma once
// The thesis's BSP partition (Cabiddu, ch. 8), built on a vertex sample: the cell holding most
// samples is split along its longest side at the median sample, until every cell's estimated
// vertex count (samples x sampling stride) is at most `vertices_per_part`. A vertex on a
// splitting plane goes to the lower side.

#include <cstddef>
#include <cstdint>
#include <vector>

#include "mesh/mesh.h"

namespace meshflow::parallel {

struct BspPartition {
  std::vector<std::uint32_t> cell_of_vertex;  // one cell id per input vertex
  std::size_t cells = 0;
  std::size_t samples = 0;
};

// \throws InvalidInput when vertices_per_part is 0.
BspPartition bsp_partition(const mesh::Mesh& input, std::size_t vertices_per_part);

}  // namespace meshflow::parallel
