#include "parallel/bsp_partition.h"

#include <algorithm>
#include <array>
#include <cmath>

#include "mesh/errors.h"

namespace meshflow::parallel {
namespace {

struct Node {
  int axis = -1;  // -1: a leaf
  float split = 0;
  std::uint32_t lower = 0, upper = 0, cell = 0;
};

struct Open {
  std::uint32_t node;
  std::vector<mesh::Point> samples;
  std::array<float, 3> lo, hi;
};

}  // namespace

BspPartition bsp_partition(const mesh::Mesh& input, std::size_t vertices_per_part) {
  if (vertices_per_part == 0) throw InvalidInput("--vertices-per-part must be at least 1");
  const std::size_t V = input.positions.size();
  // 1:1000 on large inputs; small ones keep about a thousand samples.
  const std::size_t stride = std::clamp<std::size_t>(V / 1000, 1, 1000);
  BspPartition result;
  std::vector<Node> nodes(1);
  std::vector<Open> open(1);
  open[0].node = 0;
  open[0].lo = {INFINITY, INFINITY, INFINITY};
  open[0].hi = {-INFINITY, -INFINITY, -INFINITY};
  for (std::size_t v = 0; v < V; ++v) {
    const auto& p = input.positions[v];
    for (int k = 0; k < 3; ++k) open[0].lo[k] = std::min(open[0].lo[k], p[k]), open[0].hi[k] = std::max(open[0].hi[k], p[k]);
    if (v % stride == 0) open[0].samples.push_back(p);
  }
  result.samples = open[0].samples.size();
  std::vector<Open> done;
  while (!open.empty()) {
    auto most = std::max_element(open.begin(), open.end(),
                                 [](const Open& a, const Open& b) { return a.samples.size() < b.samples.size(); });
    Open cell = std::move(*most);
    open.erase(most);
    if (cell.samples.size() * stride <= vertices_per_part || cell.samples.size() < 2) {
      done.push_back(std::move(cell));
      continue;
    }
    int axis = 0;
    for (int k = 1; k < 3; ++k)
      if (cell.hi[k] - cell.lo[k] > cell.hi[axis] - cell.lo[axis]) axis = k;
    auto mid = cell.samples.begin() + cell.samples.size() / 2;
    std::nth_element(cell.samples.begin(), mid, cell.samples.end(),
                     [axis](const mesh::Point& a, const mesh::Point& b) { return a[axis] < b[axis]; });
    float split = (*mid)[axis];
    Open lower{static_cast<std::uint32_t>(nodes.size()), {}, cell.lo, cell.hi};
    Open upper{static_cast<std::uint32_t>(nodes.size() + 1), {}, cell.lo, cell.hi};
    lower.hi[axis] = split;
    upper.lo[axis] = split;
    for (const auto& p : cell.samples) (p[axis] <= split ? lower : upper).samples.push_back(p);
    if (lower.samples.empty() || upper.samples.empty()) {  // all samples on the plane
      done.push_back(std::move(cell));
      continue;
    }
    nodes[cell.node].axis = axis;
    nodes[cell.node].split = split;
    nodes[cell.node].lower = lower.node;
    nodes[cell.node].upper = upper.node;
    nodes.emplace_back();
    nodes.emplace_back();
    open.push_back(std::move(lower));
    open.push_back(std::move(upper));
  }
  for (const Open& cell : done) nodes[cell.node].cell = static_cast<std::uint32_t>(result.cells++);
  result.cell_of_vertex.resize(V);
  for (std::size_t v = 0; v < V; ++v) {
    const auto& p = input.positions[v];
    std::uint32_t n = 0;
    while (nodes[n].axis >= 0) n = p[nodes[n].axis] <= nodes[n].split ? nodes[n].lower : nodes[n].upper;
    result.cell_of_vertex[v] = nodes[n].cell;
  }
  return result;
}

}  // namespace meshflow::parallel
