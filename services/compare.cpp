#include "services/compare.h"

#include <algorithm>
#include <cstdio>

#include "services/cgal_bridge.h"

namespace meshflow::services {

CompareResult compare(const mesh::Mesh& a, const mesh::Mesh& b, const CompareParams& params) {
  auto samples = [&](const mesh::Mesh& m) {
    auto n = static_cast<std::size_t>(params.samples_per_triangle * static_cast<double>(m.triangles.size()));
    return std::clamp(n, params.min_samples, params.max_samples);
  };
  CompareResult r;
  r.samples_a = samples(a);
  r.samples_b = samples(b);
  cgal::Distance d = cgal::surface_distance(a, b, r.samples_a, r.samples_b, params.seed);
  double diagonal = mesh::bounding_box(a).diagonal();
  double scale = diagonal > 0 ? 100.0 / diagonal : 0;
  r.mean_ab = d.mean_ab * scale;
  r.mean_ba = d.mean_ba * scale;
  r.max_ab = d.max_ab * scale;
  r.max_ba = d.max_ba * scale;
  return r;
}

std::string CompareResult::to_json() const {
  char buffer[256];
  std::snprintf(buffer, sizeof buffer,
                "{\"mean_ab\": %.9g, \"mean_ba\": %.9g, \"max_ab\": %.9g, \"max_ba\": %.9g, "
                "\"samples_a\": %zu, \"samples_b\": %zu}",
                mean_ab, mean_ba, max_ab, max_ba, samples_a, samples_b);
  return buffer;
}

}  // namespace meshflow::services
