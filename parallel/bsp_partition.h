#pragma once
// The thesis's BSP partition (Cabiddu, ch. 8), built on a vertex sample: the cell holding most
// samples is split along its longest side at the median sample, until every cell's estimated
// vertex count (samples x sampling stride) is at most `vertices_per_part`. A vertex on a
// splitting plane goes to the lower side.

#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "mesh/mesh.h"

namespace meshflow::parallel {

// The tree built on a sample; locate() puts any point in its cell.
class Bsp {
 public:
  // \throws InvalidInput when vertices_per_part is 0.
  Bsp(std::vector<mesh::Point> samples, std::size_t stride, std::array<float, 3> lo, std::array<float, 3> hi,
      std::size_t vertices_per_part);
  std::uint32_t locate(const mesh::Point& p) const;
  std::size_t cells() const { return centres_.size(); }
  // The centre of a cell's box (the thesis's case 3 picks the lexicographically smallest).
  const std::array<float, 3>& centre(std::uint32_t cell) const { return centres_[cell]; }

 private:
  struct Node {
    int axis = -1;  // -1: a leaf
    float split = 0;
    std::uint32_t lower = 0, upper = 0, cell = 0;
  };
  std::vector<Node> nodes_;
  std::vector<std::array<float, 3>> centres_;
};

struct BspPartition {
  std::vector<std::uint32_t> cell_of_vertex;  // one cell id per input vertex
  std::size_t cells = 0;
  std::size_t samples = 0;
};

// The sampling stride for a mesh of `vertices`: 1:1000 on large inputs, about a thousand samples on small ones.
std::size_t sample_stride(std::size_t vertices);

// In memory (tests and small meshes). \throws InvalidInput when vertices_per_part is 0.
BspPartition bsp_partition(const mesh::Mesh& input, std::size_t vertices_per_part);

}  // namespace meshflow::parallel
