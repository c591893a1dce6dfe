#include "parallel/distributed_simplify.h"

#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <thread>

#include <nlohmann/json.hpp>

#include "mesh/errors.h"
#include "mesh/mesh_io.h"
#include "mesh/part_files.h"

namespace meshflow::parallel {
namespace {

double since(std::chrono::steady_clock::time_point t) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
}

// `exe part-simplify DIR P --max-error-abs X`, its output in DIR/part-P.log; its last line
// is the part's stats (JSON).
services::PartStats run_worker_process(const std::string& exe, const std::string& dir, std::size_t p, double max_error,
                                       bool fixed_seams) {
  char error_text[64];
  std::snprintf(error_text, sizeof error_text, "%.17g", max_error);
  std::vector<std::string> args{exe, "part-simplify", dir, std::to_string(p), "--max-error-abs", error_text};
  if (fixed_seams) args.push_back("--fixed-seams");
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
  std::ifstream in(log);
  std::string last, line;
  while (std::getline(in, line)) last = line;
  std::filesystem::remove(log);
  return stats_from_json(nlohmann::json::parse(last, nullptr, false));
}

}  // namespace

services::PartStats stats_from_json(const nlohmann::json& s) {
  services::PartStats stats;
  if (!s.is_object()) return stats;
  stats.vertices_in = s.value("vertices_in", 0), stats.triangles_in = s.value("triangles_in", 0);
  stats.vertices_out = s.value("vertices_out", 0), stats.triangles_out = s.value("triangles_out", 0);
  stats.replayed = s.value("replayed", 0), stats.seam_removed = s.value("seam_removed", 0);
  stats.shared = s.value("shared", 0), stats.max_rms_error = s.value("max_rms_error", 0.0), stats.seconds = s.value("seconds", 0.0);
  return stats;
}

std::string DistributedReport::to_json() const {
  std::string sets = "[";
  for (const auto& set : independent_sets) {
    sets += sets.size() > 1 ? ", [" : "[";
    for (std::size_t i = 0; i < set.size(); ++i) sets += (i ? ", " : "") + std::to_string(set[i]);
    sets += "]";
  }
  sets += "]";
  std::string stats = "[";
  for (std::size_t p = 0; p < part_stats.size(); ++p) stats += (p ? ", " : "") + part_stats[p].to_json();
  stats += "]";
  std::size_t pairs = 0, replayed = 0, seam_removed = 0;
  for (const auto& n : partition.adjacency) pairs += n.size();
  for (const auto& s : part_stats) replayed += s.replayed, seam_removed += s.seam_removed;
  char buf[1200];
  std::snprintf(buf, sizeof buf,
                "{\"parts\": %zu, \"samples\": %zu, \"input_vertices\": %llu, \"input_triangles\": %llu, "
                "\"shared_vertices\": %llu, \"shared_by_3_or_more\": %llu, \"adjacent_pairs\": %zu, \"max_error_abs\": %.9g, "
                "\"shared_removed_by_half_edge_collapses\": %zu, \"shared_removed_by_replay\": %zu, "
                "\"seam_band_vertices\": %zu, \"seam_band_triangles\": %zu, \"seam_fins_removed\": %zu, \"output_vertices\": %llu, \"output_triangles\": %llu, "
                "\"seconds\": {\"partition\": %.3f, \"parts\": %.3f, \"seams\": %.3f, \"merge\": %.3f, \"total\": %.3f}, ",
                partition.parts, partition.samples, (unsigned long long)partition.input_vertices,
                (unsigned long long)partition.input_triangles, (unsigned long long)partition.shared_vertices,
                (unsigned long long)partition.shared_by_3_or_more, pairs / 2, max_error_abs, seam_removed, replayed, merge.band_vertices,
                merge.band_triangles, merge.fins_removed, (unsigned long long)merge.output_vertices, (unsigned long long)merge.output_triangles,
                partition.seconds, parts_seconds, merge.seams_seconds, merge.merge_seconds,
                partition.seconds + parts_seconds + merge.seams_seconds + merge.merge_seconds);
  return buf + std::string("\"independent_sets\": ") + sets + ", \"part_stats\": " + stats + "}\n";
}

services::PartStats simplify_one_part(const std::string& dir, std::size_t p, double max_error_abs, bool fixed_seams) {
  if (fixed_seams) return services::simplify_part_file(part_path(dir, p, false), part_path(dir, p, true), max_error_abs);
  const PartitionInfo info = read_partition_info(dir);
  if (p >= info.parts) throw InvalidInput("part " + std::to_string(p) + ": the partition has " + std::to_string(info.parts));
  // A neighbour whose Rem file for p exists is simplified (the coordinator starts p only after
  // its earlier neighbours and removes old Rem files first); the others get one from p.
  services::PartSeams seams;
  seams.part = static_cast<std::uint32_t>(p);
  for (std::uint32_t q : info.adjacency[p]) {
    const std::string in = rem_path(dir, q, p);
    if (std::filesystem::exists(in)) seams.incoming.push_back(mesh::read_rem(in));
    else seams.unsimplified.push_back(q);
  }
  // The later neighbours' sides of the seams, for the checks of the half-edge collapses there
  // (their triangles at the shared vertices only).
  for (std::uint32_t q : seams.unsimplified) {
    const std::string side = seam_path(dir, q, p);
    seams.unsimplified_parts.push_back(std::filesystem::exists(side) ? mesh::read_part(side) : mesh::PartFile{});
  }
  for (const mesh::RemFile& rem : seams.incoming)
    if (rem.from >= info.parts || rem.to != p) throw InvalidInput(rem_path(dir, rem.from, p) + ": names parts " +
                                                                  std::to_string(rem.from) + " -> " + std::to_string(rem.to));
  services::PartStats stats;
  std::vector<mesh::RemFile> outgoing;
  mesh::PartFile simplified = services::simplify_part(mesh::read_part(part_path(dir, p, false)), max_error_abs, &stats, &seams, &outgoing);
  // The Rem files first: the simplified part's presence means the part is complete.
  for (const mesh::RemFile& rem : outgoing) mesh::write_rem(rem, rem_path(dir, rem.from, rem.to));
  const std::string out = part_path(dir, p, true);
  mesh::write_part(simplified, out + ".tmp");
  std::filesystem::rename(out + ".tmp", out);
  return stats;
}

void simplify_parts(const DistributedParams& params, DistributedReport& report) {
  if (!(report.max_error_abs > 0)) throw InvalidInput("--max-error must be > 0");
  if (params.workers == 0) throw InvalidInput("--workers must be at least 1");
  auto start = std::chrono::steady_clock::now();
  // The parts in the order of the independent sets: the colour classes come in the same order
  // whatever the set size, so the order (and the result) does not depend on the worker count.
  std::vector<std::uint32_t> order;
  for (const auto& set : report.independent_sets) order.insert(order.end(), set.begin(), set.end());
  const std::size_t parts = order.size();
  const std::size_t P = report.partition.parts;
  if (parts != P) throw std::logic_error("simplify_parts: the independent sets do not cover the parts once");
  // The Rem scheme: a part starts once its neighbours earlier in the order are done. With fixed
  // seams the parts are independent: any order.
  const bool rem = !params.fixed_seams;
  std::vector<std::size_t> position(P), waiting(P, 0);
  for (std::size_t i = 0; i < parts; ++i) position[order[i]] = i;
  if (rem) {
    for (std::size_t p = 0; p < P; ++p)
      for (std::uint32_t q : report.partition.adjacency[p])
        if (position[q] < position[p]) ++waiting[p];
    // Nothing of an earlier run may pass for a simplified neighbour.
    std::error_code ec;
    for (const auto& entry : std::filesystem::directory_iterator(params.parts_dir, ec)) {
      const std::string name = entry.path().filename().string();
      if (name.rfind("rem-", 0) == 0 || name.find(".simplified.mfp") != std::string::npos) std::filesystem::remove(entry.path(), ec);
    }
  }
  report.part_stats.assign(P, {});
  std::mutex mutex;
  std::condition_variable ready;
  std::vector<std::uint8_t> started(P, 0);
  std::size_t finished = 0, running = 0, first_unstarted = 0;
  std::string error;
  auto work = [&] {
    std::unique_lock lock(mutex);
    for (;;) {
      // The earliest part not started whose earlier neighbours are done.
      std::size_t pick = parts;
      for (std::size_t i = first_unstarted; i < parts; ++i)
        if (!started[order[i]] && waiting[order[i]] == 0) {
          pick = i;
          break;
        }
      if (!error.empty() || finished + running == parts) return;
      if (pick == parts) {
        ready.wait(lock);
        continue;
      }
      const std::size_t p = order[pick];
      started[p] = 1;
      while (first_unstarted < parts && started[order[first_unstarted]]) ++first_unstarted;
      ++running;
      lock.unlock();
      services::PartStats stats;
      std::string failure;
      try {
        if (params.runner) stats = params.runner(p, report.max_error_abs, !rem);
        else if (!params.worker_executable.empty())
          stats = run_worker_process(params.worker_executable, params.parts_dir, p, report.max_error_abs, !rem);
        else stats = simplify_one_part(params.parts_dir, p, report.max_error_abs, !rem);
      } catch (const std::exception& e) {
        failure = "part " + std::to_string(p) + ": " + e.what();
      }
      lock.lock();
      --running;
      if (failure.empty()) {
        report.part_stats[p] = stats;
        ++finished;
        for (std::uint32_t q : report.partition.adjacency[p])
          if (rem && position[q] > position[p]) --waiting[q];
        if (params.progress) {
          try {
            params.progress("parts", double(finished) / double(parts));  // may throw to stop
          } catch (const std::exception& e) {
            failure = "part " + std::to_string(p) + ": " + e.what();
          }
        }
      }
      if (!failure.empty() && error.empty()) error = failure;
      ready.notify_all();
    }
  };
  std::vector<std::thread> pool;
  for (unsigned w = 0; w < std::min<std::size_t>(params.workers, parts); ++w) pool.emplace_back(work);
  for (auto& th : pool) th.join();
  if (!error.empty()) throw std::runtime_error(error);
  report.parts_seconds = since(start);
}

DistributedReport simplify_distributed(const std::string& in, const std::string& out, const DistributedParams& params) {
  if (!(params.max_error_percent > 0) && !(params.max_error_abs > 0))
    throw InvalidInput("--max-error must be > 0 (% of the diagonal)");
  if (params.workers == 0) throw InvalidInput("--workers must be at least 1");
  if (params.parts_dir.empty()) throw InvalidInput("a parts directory is needed");
  DistributedReport report;
  std::function<void(double)> partition_progress;
  if (params.progress) partition_progress = [&](double f) { params.progress("partition", f); };
  report.partition = partition_file(in, params.vertices_per_part, params.parts_dir, partition_progress);
  report.max_error_abs = params.max_error_abs > 0 ? params.max_error_abs
                                                  : params.max_error_percent / 100.0 * report.partition.diagonal;
  if (!(report.max_error_abs > 0)) throw InvalidInput(in + ": the mesh is flat to a point (zero diagonal)");
  report.independent_sets = independent_sets(report.partition.adjacency, params.workers);
  simplify_parts(params, report);
  const bool ply = out.size() >= 4 && out.compare(out.size() - 4, 4, ".ply") == 0;
  const std::string merged = ply ? out : params.parts_dir + "/merged.ply";
  report.merge = merge_parts(params.parts_dir, report.partition.parts, report.max_error_abs, merged, params.progress);
  if (!ply) mesh::write_mesh(mesh::read_mesh(merged), out);  // another format: converted in memory
  return report;
}

}  // namespace meshflow::parallel
