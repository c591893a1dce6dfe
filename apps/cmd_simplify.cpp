// meshflow simplify IN -o OUT --max-error E [--workers N | --nodes URL,...] [--vertices-per-part N]
//   [--report R.json] [--parts-dir D] [--progress]; meshflow partition IN --vertices-per-part N
//   --parts-dir D; meshflow merge D -o OUT.ply --max-error E (after `simplify --parts-dir D`).
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <mutex>
#include <sstream>
#include <thread>

#include "apps/command.h"
#include "mesh/errors.h"
#include "mesh/mesh_io.h"
#include "parallel/distributed_simplify.h"
#include "parallel/node_dispatch.h"

namespace meshflow::apps {
namespace {

struct SimplifyArgs {
  std::string in, out, report;
  double max_error = 0;
  std::size_t vertices_per_part = 1000000;
  unsigned workers = 0;
  std::string nodes;
  std::string parts_dir;
  bool progress = false;
  bool fixed_seams = false;
};

// A bar on stderr when it is a terminal (or with --progress).
std::function<void(const std::string&, double)> terminal_progress(bool forced) {
  if (!forced && !isatty(STDERR_FILENO)) return {};
  auto mutex = std::make_shared<std::mutex>();
  return [mutex](const std::string& step, double f) {
    std::lock_guard lock(*mutex);
    int filled = static_cast<int>(30 * std::clamp(f, 0.0, 1.0));
    std::fprintf(stderr, "\r%-9s [%-30.*s] %5.1f%%", step.c_str(), filled, "##############################", 100 * f);
  };
}

void add_simplify_command(CLI::App& app, int& exit_status) {
  auto args = std::make_shared<SimplifyArgs>();
  CLI::App* cmd = app.add_subcommand("simplify", "Simplify a large mesh in BSP parts, out of core (DESIGN §9)");
  cmd->add_option("IN", args->in, "Input mesh")->required();
  cmd->add_option("-o,--output", args->out, "Output mesh")->required();
  cmd->add_option("--max-error", args->max_error, "Maximum RMS error, % of the input's diagonal")->required();
  cmd->add_option("--vertices-per-part", args->vertices_per_part, "Largest part, in vertices");
  cmd->add_option("--workers", args->workers, "Local worker processes at once (default: the cores)");
  cmd->add_option("--nodes", args->nodes, "Mesh nodes (base URLs, comma-separated) that simplify the parts");
  cmd->add_option("--report", args->report, "Write parts, independent sets and per-step timings here (JSON)");
  cmd->add_option("--parts-dir", args->parts_dir, "Keep the part files here (default: a temporary folder beside OUT)");
  cmd->add_flag("--progress", args->progress, "Progress bar on stderr even when it is not a terminal");
  cmd->add_flag("--fixed-seams", args->fixed_seams,
                "Keep every shared vertex fixed (no Rem files; the seam pass alone simplifies the seams)");
  cmd->callback([args, &exit_status] {
    if (!(args->max_error > 0)) throw InvalidInput("--max-error must be > 0 (% of the diagonal)");
    parallel::DistributedParams params;
    params.fixed_seams = args->fixed_seams;
    params.max_error_percent = args->max_error;
    params.vertices_per_part = args->vertices_per_part;
    params.workers = args->workers ? args->workers : std::max(1u, std::thread::hardware_concurrency());
    params.progress = terminal_progress(args->progress);
    bool temporary = args->parts_dir.empty();
    params.parts_dir = temporary ? args->out + ".parts-" + std::to_string(getpid()) : args->parts_dir;
    struct RemoveOnExit {
      std::string dir;
      ~RemoveOnExit() {
        std::error_code ec;
        if (!dir.empty()) std::filesystem::remove_all(dir, ec);
      }
    } cleanup{temporary ? params.parts_dir : ""};
    std::unique_ptr<parallel::NodeDispatch> nodes;
    if (!args->nodes.empty()) {
      std::vector<std::string> urls;
      std::stringstream list(args->nodes);
      for (std::string url; std::getline(list, url, ',');)
        if (!url.empty()) urls.push_back(url);
      nodes = std::make_unique<parallel::NodeDispatch>(urls, std::filesystem::absolute(params.parts_dir).string());
      params.workers = static_cast<unsigned>(urls.size());
      params.runner = [&nodes](std::size_t p, double e, bool fixed_seams) { return nodes->run(p, e, fixed_seams); };
    } else {
      params.worker_executable = std::filesystem::read_symlink("/proc/self/exe").string();
    }
    parallel::DistributedReport report = parallel::simplify_distributed(args->in, args->out, params);
    if (params.progress) std::fprintf(stderr, "\n");
    if (!args->report.empty()) {
      std::ofstream r(args->report);
      r << report.to_json();
      if (!r) throw IoError("cannot write " + args->report);
    }
    std::printf("%s: %zu parts, %llu vertices, %llu triangles\n", args->out.c_str(), report.partition.parts,
                (unsigned long long)report.merge.output_vertices, (unsigned long long)report.merge.output_triangles);
    exit_status = 0;
  });
}

void add_partition_command(CLI::App& app, int& exit_status) {
  auto args = std::make_shared<SimplifyArgs>();
  CLI::App* cmd = app.add_subcommand("partition", "Cut a mesh into BSP part files, out of core (DESIGN §9)");
  cmd->add_option("IN", args->in, "Input mesh")->required();
  cmd->add_option("--vertices-per-part", args->vertices_per_part, "Largest part, in vertices")->required();
  cmd->add_option("--parts-dir", args->parts_dir, "Folder for part-<i>.mfp")->required();
  cmd->add_flag("--progress", args->progress, "Progress bar on stderr even when it is not a terminal");
  cmd->callback([args, &exit_status] {
    auto bar = terminal_progress(args->progress);
    std::function<void(double)> progress;
    if (bar) progress = [&](double f) { bar("partition", f); };
    parallel::PartitionInfo info = parallel::partition_file(args->in, args->vertices_per_part, args->parts_dir, progress);
    if (bar) std::fprintf(stderr, "\n");
    std::printf("%zu parts, %llu shared vertices, in %s\n", info.parts, (unsigned long long)info.shared_vertices,
                args->parts_dir.c_str());
    exit_status = 0;
  });
}

void add_merge_command(CLI::App& app, int& exit_status) {
  auto args = std::make_shared<SimplifyArgs>();
  CLI::App* cmd = app.add_subcommand("merge", "Simplify the seams of simplified part files and merge them into one PLY, out of core");
  cmd->add_option("PARTS_DIR", args->parts_dir, "Folder of part-<i>.simplified.mfp (simplify --parts-dir)")->required();
  cmd->add_option("-o,--output", args->out, "Output mesh (.ply)")->required();
  cmd->add_option("--max-error", args->max_error, "Maximum RMS error, % of the input's diagonal")->required();
  cmd->add_flag("--progress", args->progress, "Progress bar on stderr even when it is not a terminal");
  cmd->callback([args, &exit_status] {
    if (!(args->max_error > 0)) throw InvalidInput("--max-error must be > 0 (% of the diagonal)");
    if (args->out.size() < 4 || args->out.compare(args->out.size() - 4, 4, ".ply") != 0)
      throw InvalidInput(args->out + ": merge writes canonical PLY; name the output *.ply");
    parallel::PartitionInfo info = parallel::read_partition_info(args->parts_dir);
    auto bar = terminal_progress(args->progress);
    parallel::MergeReport r = parallel::merge_parts(args->parts_dir, info.parts, args->max_error / 100.0 * info.diagonal, args->out, bar);
    if (bar) std::fprintf(stderr, "\n");
    std::printf("%s: %llu vertices, %llu triangles\n", args->out.c_str(), (unsigned long long)r.output_vertices,
                (unsigned long long)r.output_triangles);
    exit_status = 0;
  });
}

// The worker process of `simplify`: one part file and its incoming Rem files in, its simplified
// part file and its outgoing Rem files out (DIR/rem-<from>-<to>.bin).
void add_part_simplify_command(CLI::App& app, int& exit_status) {
  auto dir = std::make_shared<std::string>();
  auto part = std::make_shared<std::size_t>(0);
  auto max_error = std::make_shared<double>(0);
  auto fixed = std::make_shared<bool>(false);
  CLI::App* cmd = app.add_subcommand("part-simplify", "Worker of simplify: DIR/part-P.mfp and DIR/rem-*-P.bin -> DIR/part-P.simplified.mfp and DIR/rem-P-*.bin");
  cmd->add_option("DIR", *dir, "Parts directory")->required();
  cmd->add_option("P", *part, "Part number")->required();
  cmd->add_option("--max-error-abs", *max_error, "Maximum RMS error, absolute")->required();
  cmd->add_flag("--fixed-seams", *fixed, "Keep every shared vertex fixed; no Rem files read or written");
  cmd->callback([dir, part, max_error, fixed, &exit_status] {
    if (*max_error <= 0) throw InvalidInput("--max-error-abs must be > 0");
    std::printf("%s\n", parallel::simplify_one_part(*dir, *part, *max_error, *fixed).to_json().c_str());
    exit_status = 0;
  });
}

}  // namespace

MESHFLOW_COMMAND(part_simplify, add_part_simplify_command);
MESHFLOW_COMMAND(simplify, add_simplify_command);
MESHFLOW_COMMAND(partition, add_partition_command);
MESHFLOW_COMMAND(merge, add_merge_command);

}  // namespace meshflow::apps
