#include "services/compare.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>

#include "mesh/index_hash.h"
#include "mesh/mesh_io.h"

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

namespace {

class VertexDistanceSink : public mesh::MeshSink {
 public:
  VertexDistanceSink(const mesh::Mesh& b, std::size_t max_samples) : distance_(b), max_samples_(max_samples) {}
  void begin(mesh::Format, std::int64_t vertex_count, std::int64_t) override {
    if (vertex_count > 0 && static_cast<std::uint64_t>(vertex_count) > max_samples_)
      stride_ = (static_cast<std::uint64_t>(vertex_count) + max_samples_ - 1) / max_samples_;
  }
  void vertices(std::span<const mesh::Point> batch) override {
    for (const auto& p : batch) {
      for (int k = 0; k < 3; ++k) lo[k] = std::min(lo[k], double(p[k])), hi[k] = std::max(hi[k], double(p[k]));
      if (mesh::index_hash(index_++) % stride_ != 0) continue;
      double d = distance_(p);
      sum += d, max = std::max(max, d), ++samples;
    }
  }
  void triangles(std::span<const mesh::Triangle>) override {}
  bool wants_triangles() const override { return false; }

  double sum = 0, max = 0;
  std::size_t samples = 0;
  std::array<double, 3> lo{INFINITY, INFINITY, INFINITY}, hi{-INFINITY, -INFINITY, -INFINITY};

 private:
  cgal::DistanceToSurface distance_;
  std::size_t max_samples_;
  std::uint64_t stride_ = 1, index_ = 0;
};

}  // namespace

CompareResult compare_one_way(const std::string& a_path, const mesh::Mesh& b, const CompareParams& params) {
  VertexDistanceSink sink(b, std::max<std::size_t>(params.max_samples, 1));
  mesh::stream_mesh(a_path, sink);
  CompareResult r;
  r.one_way = true;
  r.samples_a = sink.samples;
  if (sink.samples == 0) return r;
  double diagonal = std::sqrt(std::pow(sink.hi[0] - sink.lo[0], 2) + std::pow(sink.hi[1] - sink.lo[1], 2) +
                              std::pow(sink.hi[2] - sink.lo[2], 2));
  double scale = diagonal > 0 ? 100.0 / diagonal : 0;
  r.mean_ab = sink.sum / double(sink.samples) * scale;
  r.max_ab = sink.max * scale;
  return r;
}

std::string CompareResult::to_json() const {
  char buffer[256];
  if (one_way) {
    std::snprintf(buffer, sizeof buffer, "{\"mean_ab\": %.9g, \"max_ab\": %.9g, \"samples_a\": %zu, \"one_way\": true}",
                  mean_ab, max_ab, samples_a);
    return buffer;
  }
  std::snprintf(buffer, sizeof buffer,
                "{\"mean_ab\": %.9g, \"mean_ba\": %.9g, \"max_ab\": %.9g, \"max_ba\": %.9g, "
                "\"samples_a\": %zu, \"samples_b\": %zu}",
                mean_ab, mean_ba, max_ab, max_ba, samples_a, samples_b);
  return buffer;
}

}  // namespace meshflow::services
