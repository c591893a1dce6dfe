#include "parallel/distributed_simplify.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>
#include <filesystem>
#include <limits>
#include <mutex>
#include <thread>
#include <unordered_map>

#include "mesh/errors.h"
#include "mesh/part_files.h"
#include "parallel/bsp_partition.h"
#include "services/simplify.h"

namespace meshflow::parallel {
namespace {

using mesh::Index;
constexpr Index kNone = std::numeric_limits<Index>::max();

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}


}  // namespace

std::string DistributedReport::to_json() const {
  std::string sets = "[";
  for (const auto& set : independent_sets) {
    sets += sets.size() > 1 ? ", [" : "[";
    for (std::size_t i = 0; i < set.size(); ++i) sets += (i ? ", " : "") + std::to_string(set[i]);
    sets += "]";
  }
  sets += "]";
  std::size_t pairs = 0;
  for (const auto& n : adjacency) pairs += n.size();
  char buf[512];
  std::snprintf(buf, sizeof buf,
                "{\"parts\": %zu, \"samples\": %zu, \"seam_vertices\": %zu, \"merged_vertices\": %zu, "
                "\"output_vertices\": %zu, \"adjacent_pairs\": %zu, \"seconds\": {\"partition\": %.3f, \"parts\": %.3f, \"merge\": %.3f, "
                "\"seams\": %.3f, \"total\": %.3f}, \"independent_sets\": ",
                parts, samples, seam_vertices, merged_vertices, output_vertices, pairs / 2, partition_seconds, parts_seconds,
                merge_seconds, seams_seconds, partition_seconds + parts_seconds + merge_seconds + seams_seconds);
  return buf + sets + "}\n";
}

namespace {

std::string part_path(const std::string& dir, std::size_t p, bool simplified) {
  return dir + "/part-" + std::to_string(p) + (simplified ? ".simplified.mfp" : ".mfp");
}

}  // namespace

std::size_t partition_to_files(const mesh::Mesh& input, std::size_t vertices_per_part, const std::string& dir,
                               DistributedReport& report) {
  const std::size_t V = input.positions.size();
  for (const auto& tri : input.triangles)
    for (Index v : tri)
      if (v >= V) throw InvalidInput("triangle refers to vertex " + std::to_string(v) + " of " + std::to_string(V));
  std::filesystem::create_directories(dir);
  auto start = std::chrono::steady_clock::now();
  // Vertices by BSP cell, a triangle to the lowest cell among its vertices (the vertices of
  // other cells go with it as copies).
  BspPartition bsp = bsp_partition(input, vertices_per_part);
  std::vector<std::vector<Index>> triangles_of(bsp.cells);
  for (std::size_t t = 0; t < input.triangles.size(); ++t) {
    const auto& tri = input.triangles[t];
    std::uint32_t cell = std::min({bsp.cell_of_vertex[tri[0]], bsp.cell_of_vertex[tri[1]], bsp.cell_of_vertex[tri[2]]});
    triangles_of[cell].push_back(static_cast<Index>(t));
  }
  bsp.cell_of_vertex = {};
  std::erase_if(triangles_of, [](const auto& ts) { return ts.empty(); });
  // A vertex used by triangles of two or more parts is shared (a seam vertex).
  constexpr std::uint32_t kNoPart = std::numeric_limits<std::uint32_t>::max();
  std::vector<std::uint32_t> first_part(V, kNoPart);
  std::vector<bool> seam(V, false);
  for (std::uint32_t p = 0; p < triangles_of.size(); ++p)
    for (Index t : triangles_of[p])
      for (Index v : input.triangles[t]) {
        if (first_part[v] == kNoPart) first_part[v] = p;
        else if (first_part[v] != p) seam[v] = true;
      }
  first_part = {};
  std::vector<Index> local(V, kNone);
  std::vector<std::pair<Index, std::uint32_t>> shared_uses;  // (seam vertex, part)
  for (std::size_t p = 0; p < triangles_of.size(); ++p) {
    mesh::PartFile part;
    std::vector<Index> ids;
    for (Index t : triangles_of[p])
      for (Index v : input.triangles[t]) ids.push_back(v);
    std::sort(ids.begin(), ids.end());
    ids.erase(std::unique(ids.begin(), ids.end()), ids.end());
    for (std::size_t i = 0; i < ids.size(); ++i) {
      local[ids[i]] = static_cast<Index>(i);
      part.global_ids.push_back(ids[i]);
      part.positions.push_back(input.positions[ids[i]]);
      part.shared.push_back(seam[ids[i]]);
      if (seam[ids[i]]) shared_uses.emplace_back(ids[i], static_cast<std::uint32_t>(p));
    }
    for (Index t : triangles_of[p]) {
      const auto& tri = input.triangles[t];
      part.triangles.push_back({local[tri[0]], local[tri[1]], local[tri[2]]});
    }
    for (Index v : ids) local[v] = kNone;
    mesh::write_part(part, part_path(dir, p, false));
    triangles_of[p] = {};
  }
  // Parts sharing a vertex are adjacent.
  std::sort(shared_uses.begin(), shared_uses.end());
  report.adjacency.assign(triangles_of.size(), {});
  for (std::size_t i = 0; i < shared_uses.size();) {
    std::size_t j = i;
    while (j < shared_uses.size() && shared_uses[j].first == shared_uses[i].first) ++j;
    for (std::size_t a = i; a < j; ++a)
      for (std::size_t b = i; b < j; ++b)
        if (a != b) report.adjacency[shared_uses[a].second].push_back(shared_uses[b].second);
    i = j;
  }
  for (auto& neighbours : report.adjacency) {
    std::sort(neighbours.begin(), neighbours.end());
    neighbours.erase(std::unique(neighbours.begin(), neighbours.end()), neighbours.end());
  }
  report.parts = triangles_of.size();
  report.samples = bsp.samples;
  report.seam_vertices = std::count(seam.begin(), seam.end(), true);
  report.partition_seconds = seconds_since(start);
  return report.parts;
}

void simplify_one_part(const std::string& dir, std::size_t p, double max_error) {
  mesh::PartFile part = mesh::read_part(part_path(dir, p, false));
  mesh::Mesh m{std::move(part.positions), std::move(part.triangles)};
  std::vector<bool> locked(part.shared.begin(), part.shared.end());
  services::SimplifyParams sp;
  sp.max_error = max_error;
  sp.locked = &locked;
  sp.export_quadrics = true;
  services::SimplifyResult r = services::simplify(m, sp);
  mesh::PartFile out;
  for (Index i : r.source_ids) {
    out.global_ids.push_back(part.global_ids[i]);
    out.shared.push_back(part.shared[i]);
  }
  out.positions = std::move(r.output.positions);
  out.triangles = std::move(r.output.triangles);
  out.quadrics = std::move(r.quadrics);
  mesh::write_part(out, part_path(dir, p, true));
}

namespace {

// `exe part-simplify DIR P --max-error-abs X`, its output in DIR/part-P.log.
void run_worker_process(const std::string& exe, const std::string& dir, std::size_t p, double max_error) {
  char error_text[64];
  std::snprintf(error_text, sizeof error_text, "%.17g", max_error);
  std::vector<std::string> args{exe, "part-simplify", dir, std::to_string(p), "--max-error-abs", error_text};
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  std::string log = dir + "/part-" + std::to_string(p) + ".log";
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, STDOUT_FILENO, log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_adddup2(&actions, STDOUT_FILENO, STDERR_FILENO);
  pid_t pid;
  int rc = posix_spawn(&pid, exe.c_str(), &actions, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  if (rc != 0) throw IoError("cannot start the worker " + exe + ": " + std::strerror(rc));
  int status = 0;
  while (waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) {
    std::ifstream in(log);
    std::string last, line;
    while (std::getline(in, line)) last = line;
    throw std::runtime_error("worker process failed (" + log + "): " + last);
  }
}

}  // namespace

void simplify_part_files(const std::string& dir, std::size_t parts, const DistributedParams& params,
                         DistributedReport& report) {
  if (params.max_error <= 0) throw InvalidInput("--max-error must be > 0");
  if (params.workers == 0) throw InvalidInput("--workers must be at least 1");
  auto start = std::chrono::steady_clock::now();
  std::atomic<std::size_t> next{0}, finished{0};
  std::mutex error_mutex;
  std::string error;
  auto work = [&] {
    for (std::size_t p; (p = next++) < parts;) {
      try {
        if (params.worker_executable.empty()) simplify_one_part(dir, p, params.max_error);
        else run_worker_process(params.worker_executable, dir, p, params.max_error);
      } catch (const std::exception& e) {
        std::lock_guard lock(error_mutex);
        error = "part " + std::to_string(p) + ": " + e.what();
      }
      std::size_t n = ++finished;
      if (params.progress) params.progress("parts", double(n) / double(parts));
    }
  };
  std::vector<std::thread> pool;
  for (unsigned w = 0; w < std::min<std::size_t>(params.workers, parts); ++w) pool.emplace_back(work);
  for (auto& th : pool) th.join();
  if (!error.empty()) throw std::runtime_error(error);
  report.parts_seconds = seconds_since(start);
}

mesh::Mesh merge_part_files(const std::string& dir, std::size_t parts, const DistributedParams& params,
                            DistributedReport& report) {
  if (params.max_error <= 0) throw InvalidInput("--max-error must be > 0");
  // Merge by global id; only shared vertices need a lookup, their quadrics add up.
  auto start = std::chrono::steady_clock::now();
  std::unordered_map<std::uint64_t, Index> shared_id;
  mesh::Mesh merged;
  std::vector<std::array<double, 11>> quadrics;
  std::vector<bool> merged_seam;
  for (std::size_t p = 0; p < parts; ++p) {
    mesh::PartFile part = mesh::read_part(part_path(dir, p, true));
    if (part.quadrics.size() != part.positions.size())
      throw InvalidInput(part_path(dir, p, true) + ": a simplified part must carry its quadrics");
    std::vector<Index> to_merged(part.positions.size());
    for (std::size_t i = 0; i < part.positions.size(); ++i) {
      Index id = static_cast<Index>(merged.positions.size());
      if (part.shared[i]) {
        auto [it, added] = shared_id.try_emplace(part.global_ids[i], id);
        if (!added) {
          auto& q = quadrics[it->second];
          for (int k = 0; k < 11; ++k) q[k] += part.quadrics[i][k];
          to_merged[i] = it->second;
          continue;
        }
      }
      merged.positions.push_back(part.positions[i]);
      quadrics.push_back(part.quadrics[i]);
      merged_seam.push_back(part.shared[i]);
      to_merged[i] = id;
    }
    for (const auto& tri : part.triangles)
      merged.triangles.push_back({to_merged[tri[0]], to_merged[tri[1]], to_merged[tri[2]]});
  }
  shared_id = {};
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

mesh::Mesh simplify_distributed(const mesh::Mesh& input, const DistributedParams& params, DistributedReport& report) {
  if (params.max_error <= 0) throw InvalidInput("--max-error must be > 0");
  if (params.workers == 0) throw InvalidInput("--workers must be at least 1");
  if (params.parts_dir.empty()) throw InvalidInput("a parts directory is needed");
  std::size_t parts = partition_to_files(input, params.vertices_per_part, params.parts_dir, report);
  simplify_part_files(params.parts_dir, parts, params, report);
  return merge_part_files(params.parts_dir, parts, params, report);
}

}  // namespace meshflow::parallel
