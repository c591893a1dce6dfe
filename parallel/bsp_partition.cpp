#include "parallel/bsp_partition.h"

#include <algorithm>
#include <cmath>

#include "mesh/errors.h"

namespace meshflow::parallel {
namespace {

struct Open {
  std::uint32_t node;
  std::vector<mesh::Point> samples;
  std::array<float, 3> lo, hi;
};

}  // namespace

std::size_t sample_stride(std::size_t vertices) { return std::clamp<std::size_t>(vertices / 1000, 1, 1000); }

Bsp::Bsp(std::vector<mesh::Point> samples, std::size_t stride, std::array<float, 3> lo, std::array<float, 3> hi,
         std::size_t vertices_per_part) {
  if (vertices_per_part == 0) throw InvalidInput("--vertices-per-part must be at least 1");
  nodes_.resize(1);
  std::vector<Open> open(1);
  open[0] = {0, std::move(samples), lo, hi};
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
    // The longest side first; a median equal to the side's largest sample (many samples on one
    // plane, e.g. a regular grid) splits just below it instead; a side where every sample
    // has the same coordinate gives way to the next longest.
    std::array<int, 3> axes{0, 1, 2};
    std::stable_sort(axes.begin(), axes.end(), [&](int a, int b) { return cell.hi[a] - cell.lo[a] > cell.hi[b] - cell.lo[b]; });
    int axis = -1;
    float split = 0;
    for (int k : axes) {
      auto mid = cell.samples.begin() + cell.samples.size() / 2;
      std::nth_element(cell.samples.begin(), mid, cell.samples.end(),
                       [k](const mesh::Point& a, const mesh::Point& b) { return a[k] < b[k]; });
      float median = (*mid)[k];
      float below = -INFINITY, above = -INFINITY;  // the largest sample under the median; the largest overall
      for (const auto& p : cell.samples) {
        if (p[k] < median) below = std::max(below, p[k]);
        above = std::max(above, p[k]);
      }
      if (above > median) axis = k, split = median;
      else if (below > -INFINITY) axis = k, split = below;
      if (axis >= 0) break;
    }
    if (axis < 0) {  // every sample at one point
      done.push_back(std::move(cell));
      continue;
    }
    Open lower{static_cast<std::uint32_t>(nodes_.size()), {}, cell.lo, cell.hi};
    Open upper{static_cast<std::uint32_t>(nodes_.size() + 1), {}, cell.lo, cell.hi};
    lower.hi[axis] = split;
    upper.lo[axis] = split;
    for (const auto& p : cell.samples) (p[axis] <= split ? lower : upper).samples.push_back(p);
    nodes_[cell.node].axis = axis;
    nodes_[cell.node].split = split;
    nodes_[cell.node].lower = lower.node;
    nodes_[cell.node].upper = upper.node;
    nodes_.emplace_back();
    nodes_.emplace_back();
    open.push_back(std::move(lower));
    open.push_back(std::move(upper));
  }
  // Cells numbered in tree order, so the numbering does not depend on the order of `done`.
  std::sort(done.begin(), done.end(), [](const Open& a, const Open& b) { return a.node < b.node; });
  for (const Open& cell : done) {
    nodes_[cell.node].cell = static_cast<std::uint32_t>(centres_.size());
    centres_.push_back({(cell.lo[0] + cell.hi[0]) / 2, (cell.lo[1] + cell.hi[1]) / 2, (cell.lo[2] + cell.hi[2]) / 2});
  }
}

std::uint32_t Bsp::locate(const mesh::Point& p) const {
  std::uint32_t n = 0;
  while (nodes_[n].axis >= 0) n = p[nodes_[n].axis] <= nodes_[n].split ? nodes_[n].lower : nodes_[n].upper;
  return nodes_[n].cell;
}

BspPartition bsp_partition(const mesh::Mesh& input, std::size_t vertices_per_part) {
  if (vertices_per_part == 0) throw InvalidInput("--vertices-per-part must be at least 1");
  const std::size_t V = input.positions.size();
  const std::size_t stride = sample_stride(V);
  std::array<float, 3> lo{INFINITY, INFINITY, INFINITY}, hi{-INFINITY, -INFINITY, -INFINITY};
  std::vector<mesh::Point> samples;
  for (std::size_t v = 0; v < V; ++v) {
    const auto& p = input.positions[v];
    for (int k = 0; k < 3; ++k) lo[k] = std::min(lo[k], p[k]), hi[k] = std::max(hi[k], p[k]);
    if (v % stride == 0) samples.push_back(p);
  }
  BspPartition result;
  result.samples = samples.size();
  Bsp bsp(std::move(samples), stride, lo, hi, vertices_per_part);
  result.cells = bsp.cells();
  result.cell_of_vertex.resize(V);
  for (std::size_t v = 0; v < V; ++v) result.cell_of_vertex[v] = bsp.locate(input.positions[v]);
  return result;
}

}  // namespace meshflow::parallel
