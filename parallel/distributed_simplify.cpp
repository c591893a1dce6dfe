#include "parallel/distributed_simplify.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <limits>
#include <mutex>
#include <thread>

#include "mesh/errors.h"
#include "parallel/bsp_partition.h"
#include "services/simplify.h"

namespace meshflow::parallel {
namespace {

using mesh::Index;
constexpr Index kNone = std::numeric_limits<Index>::max();

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

struct Part {
  std::vector<Index> triangles;      // input triangle ids
  std::vector<Index> global_ids;     // local vertex -> input vertex, ascending
  services::SimplifyResult result;
};

}  // namespace

std::string DistributedReport::to_json() const {
  char buf[512];
  std::snprintf(buf, sizeof buf,
                "{\"parts\": %zu, \"samples\": %zu, \"seam_vertices\": %zu, \"merged_vertices\": %zu, "
                "\"output_vertices\": %zu, \"seconds\": {\"partition\": %.3f, \"parts\": %.3f, \"merge\": %.3f, "
                "\"seams\": %.3f, \"total\": %.3f}}\n",
                parts, samples, seam_vertices, merged_vertices, output_vertices, partition_seconds, parts_seconds,
                merge_seconds, seams_seconds, partition_seconds + parts_seconds + merge_seconds + seams_seconds);
  return buf;
}

mesh::Mesh simplify_distributed(const mesh::Mesh& input, const DistributedParams& params, DistributedReport& report) {
  if (params.max_error <= 0) throw InvalidInput("--max-error must be > 0");
  if (params.workers == 0) throw InvalidInput("--workers must be at least 1");
  const std::size_t V = input.positions.size();
  for (const auto& tri : input.triangles)
    for (Index v : tri)
      if (v >= V) throw InvalidInput("triangle refers to vertex " + std::to_string(v) + " of " + std::to_string(V));

  // Partition: vertices by BSP cell, a triangle to the lowest cell among its vertices (the
  // vertices of other cells go with it as copies).
  auto start = std::chrono::steady_clock::now();
  BspPartition bsp = bsp_partition(input, params.vertices_per_part);
  std::vector<Part> parts(bsp.cells);
  for (std::size_t t = 0; t < input.triangles.size(); ++t) {
    const auto& tri = input.triangles[t];
    std::uint32_t cell = std::min({bsp.cell_of_vertex[tri[0]], bsp.cell_of_vertex[tri[1]], bsp.cell_of_vertex[tri[2]]});
    parts[cell].triangles.push_back(static_cast<Index>(t));
  }
  // A vertex used by triangles of two or more parts is a seam vertex.
  std::vector<std::uint32_t> first_part(V, std::numeric_limits<std::uint32_t>::max());
  std::vector<bool> seam(V, false);
  for (std::uint32_t p = 0; p < parts.size(); ++p)
    for (Index t : parts[p].triangles)
      for (Index v : input.triangles[t]) {
        if (first_part[v] == std::numeric_limits<std::uint32_t>::max()) first_part[v] = p;
        else if (first_part[v] != p) seam[v] = true;
      }
  first_part = {};
  report.parts = std::count_if(parts.begin(), parts.end(), [](const Part& p) { return !p.triangles.empty(); });
  report.samples = bsp.samples;
  report.seam_vertices = std::count(seam.begin(), seam.end(), true);
  report.partition_seconds = seconds_since(start);

  // Parts, simplified by the worker pool with their seam vertices fixed.
  start = std::chrono::steady_clock::now();
  std::atomic<std::size_t> next{0}, finished{0};
  std::mutex error_mutex;
  std::string error;
  auto work = [&] {
    std::vector<Index> local(V, kNone);
    for (std::size_t p; (p = next++) < parts.size();) {
      Part& part = parts[p];
      if (part.triangles.empty()) continue;
      try {
        for (Index t : part.triangles)
          for (Index v : input.triangles[t]) part.global_ids.push_back(v);
        std::sort(part.global_ids.begin(), part.global_ids.end());
        part.global_ids.erase(std::unique(part.global_ids.begin(), part.global_ids.end()), part.global_ids.end());
        mesh::Mesh m;
        std::vector<bool> locked(part.global_ids.size());
        for (std::size_t i = 0; i < part.global_ids.size(); ++i) {
          Index g = part.global_ids[i];
          local[g] = static_cast<Index>(i);
          m.positions.push_back(input.positions[g]);
          locked[i] = seam[g];
        }
        for (Index t : part.triangles) {
          const auto& tri = input.triangles[t];
          m.triangles.push_back({local[tri[0]], local[tri[1]], local[tri[2]]});
        }
        for (Index g : part.global_ids) local[g] = kNone;
        services::SimplifyParams sp;
        sp.max_error = params.max_error;
        sp.locked = &locked;
        sp.export_quadrics = true;
        part.result = services::simplify(m, sp);
        part.triangles = {};
      } catch (const std::exception& e) {
        std::lock_guard lock(error_mutex);
        error = "part " + std::to_string(p) + ": " + e.what();
      }
      std::size_t n = ++finished;
      if (params.progress) params.progress("parts", double(n) / double(parts.size()));
    }
  };
  std::vector<std::thread> pool;
  for (unsigned w = 0; w < std::min<std::size_t>(params.workers, parts.size()); ++w) pool.emplace_back(work);
  for (auto& th : pool) th.join();
  if (!error.empty()) throw std::runtime_error(error);
  report.parts_seconds = seconds_since(start);

  // Merge by global id; a seam vertex's quadrics from every part add up.
  start = std::chrono::steady_clock::now();
  std::vector<Index> merged_id(V, kNone);
  mesh::Mesh merged;
  std::vector<std::array<double, 11>> quadrics;
  std::vector<bool> merged_seam;
  for (Part& part : parts) {
    const auto& r = part.result;
    std::vector<Index> to_merged(r.output.positions.size());
    for (std::size_t i = 0; i < r.output.positions.size(); ++i) {
      Index g = part.global_ids[r.source_ids[i]];
      if (merged_id[g] == kNone) {
        merged_id[g] = static_cast<Index>(merged.positions.size());
        merged.positions.push_back(r.output.positions[i]);
        quadrics.push_back(r.quadrics[i]);
        merged_seam.push_back(seam[g]);
      } else {
        auto& q = quadrics[merged_id[g]];
        for (int k = 0; k < 11; ++k) q[k] += r.quadrics[i][k];
      }
      to_merged[i] = merged_id[g];
    }
    for (const auto& tri : r.output.triangles)
      merged.triangles.push_back({to_merged[tri[0]], to_merged[tri[1]], to_merged[tri[2]]});
    part = Part{};
  }
  merged_id = {};
  report.merged_vertices = merged.positions.size();
  report.merge_seconds = seconds_since(start);

  // The seams, with the accumulated quadrics.
  start = std::chrono::steady_clock::now();
  services::SimplifyParams sp;
  sp.max_error = params.max_error;
  sp.quadrics = &quadrics;
  sp.seam = &merged_seam;
  if (params.progress) sp.progress = [&](double f) { params.progress("seams", f); };
  mesh::Mesh out = services::simplify(merged, sp).output;
  report.output_vertices = out.positions.size();
  report.seams_seconds = seconds_since(start);
  return out;
}

}  // namespace meshflow::parallel
