// meshflow simplify IN -o OUT --max-error E [--workers N] [--vertices-per-part N] [--report R.json]
//   [--parts-dir D]; meshflow partition IN --vertices-per-part N --parts-dir D;
// meshflow merge D -o OUT --max-error E (after `simplify --parts-dir D`).
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <thread>

#include "apps/command.h"
#include "mesh/errors.h"
#include "mesh/mesh_io.h"
#include "parallel/distributed_simplify.h"

namespace meshflow::apps {
namespace {

struct SimplifyArgs {
  std::string in, out, report;
  double max_error = 0;
  std::size_t vertices_per_part = 1000000;
  unsigned workers = 0;
  std::string node_urls;
  std::string parts_dir;
};

// D/partition.txt: what the merge needs from the partition.
void write_partition_info(const std::string& dir, std::size_t parts, double diagonal) {
  std::ofstream out(dir + "/partition.txt");
  out.precision(17);  // the diagonal round-trips exactly, whatever the mesh's scale
  out << "parts " << parts << "\ndiagonal " << diagonal << "\n";
  if (!out) throw IoError(dir + "/partition.txt: cannot write");
}

void read_partition_info(const std::string& dir, std::size_t& parts, double& diagonal) {
  std::ifstream in(dir + "/partition.txt");
  std::string k1, k2;
  if (!(in >> k1 >> parts >> k2 >> diagonal) || k1 != "parts" || k2 != "diagonal")
    throw InvalidInput(dir + "/partition.txt: expected \"parts N\" and \"diagonal X\" (written by meshflow partition)");
}

std::function<void(const std::string&, double)> terminal_progress() {
  if (!isatty(STDERR_FILENO)) return {};
  return [](const std::string& step, double f) {
    int filled = static_cast<int>(30 * f);
    std::fprintf(stderr, "\r%-6s [%-30.*s] %5.1f%%", step.c_str(), filled, "##############################", 100 * f);
  };
}

void add_simplify_command(CLI::App& app, int& exit_status) {
  auto args = std::make_shared<SimplifyArgs>();
  CLI::App* cmd = app.add_subcommand("simplify", "Simplify a large mesh in BSP parts (DESIGN §9)");
  cmd->add_option("IN", args->in, "Input mesh")->required();
  cmd->add_option("-o,--output", args->out, "Output mesh")->required();
  cmd->add_option("--max-error", args->max_error, "Maximum RMS error, % of the input's diagonal")->required();
  cmd->add_option("--vertices-per-part", args->vertices_per_part, "Largest part, in vertices");
  cmd->add_option("--workers", args->workers, "Parts simplified at once (default: the cores)");
  cmd->add_option("--node-urls,--nodes", args->node_urls, "Mesh nodes (not implemented yet)");
  cmd->add_option("--report", args->report, "Write parts and per-step timings here (JSON)");
  cmd->add_option("--parts-dir", args->parts_dir, "Keep the part files here (default: a temporary folder beside OUT)");
  cmd->callback([args, &exit_status] {
    if (!args->node_urls.empty())
      throw InvalidInput("--node-urls: dispatch to mesh nodes is not implemented yet; use --workers");
    if (args->max_error <= 0) throw InvalidInput("--max-error must be > 0 (% of the diagonal)");
    mesh::Mesh input = mesh::read_mesh(args->in);
    const double diagonal = mesh::bounding_box(input).diagonal();
    parallel::DistributedParams params;
    params.max_error = args->max_error / 100.0 * diagonal;
    params.vertices_per_part = args->vertices_per_part;
    params.workers = args->workers ? args->workers : std::max(1u, std::thread::hardware_concurrency());
    params.progress = terminal_progress();
    params.worker_executable = std::filesystem::read_symlink("/proc/self/exe").string();
    bool temporary = args->parts_dir.empty();
    params.parts_dir = temporary ? args->out + ".parts-" + std::to_string(getpid()) : args->parts_dir;
    struct RemoveOnExit {
      std::string dir;
      ~RemoveOnExit() {
        std::error_code ec;
        if (!dir.empty()) std::filesystem::remove_all(dir, ec);
      }
    } cleanup{temporary ? params.parts_dir : ""};
    parallel::DistributedReport report;
    std::size_t parts = parallel::partition_to_files(input, params.vertices_per_part, params.parts_dir, report);
    write_partition_info(params.parts_dir, parts, diagonal);
    input = {};
    report.independent_sets = parallel::independent_sets(report.adjacency, params.workers);
    parallel::simplify_part_files(params.parts_dir, parts, params, report);
    mesh::Mesh output = parallel::merge_part_files(params.parts_dir, parts, params, report);
    if (params.progress) std::fprintf(stderr, "\n");
    mesh::write_mesh(output, args->out);
    if (!args->report.empty()) {
      std::ofstream r(args->report);
      r << report.to_json();
      if (!r) throw std::runtime_error("cannot write " + args->report);
    }
    std::printf("%s: %zu parts, %zu vertices, %zu triangles\n", args->out.c_str(), report.parts,
                output.positions.size(), output.triangles.size());
    exit_status = 0;
  });
}

void add_partition_command(CLI::App& app, int& exit_status) {
  auto args = std::make_shared<SimplifyArgs>();
  CLI::App* cmd = app.add_subcommand("partition", "Cut a mesh into BSP part files (DESIGN §9)");
  cmd->add_option("IN", args->in, "Input mesh")->required();
  cmd->add_option("--vertices-per-part", args->vertices_per_part, "Largest part, in vertices")->required();
  cmd->add_option("--parts-dir", args->parts_dir, "Folder for part-<i>.mfp")->required();
  cmd->callback([args, &exit_status] {
    mesh::Mesh input = mesh::read_mesh(args->in);
    parallel::DistributedReport report;
    std::size_t parts = parallel::partition_to_files(input, args->vertices_per_part, args->parts_dir, report);
    write_partition_info(args->parts_dir, parts, mesh::bounding_box(input).diagonal());
    std::printf("%zu parts, %zu shared vertices, in %s\n", parts, report.seam_vertices, args->parts_dir.c_str());
    exit_status = 0;
  });
}

void add_merge_command(CLI::App& app, int& exit_status) {
  auto args = std::make_shared<SimplifyArgs>();
  CLI::App* cmd = app.add_subcommand("merge", "Merge simplified part files and simplify their seams");
  cmd->add_option("PARTS_DIR", args->parts_dir, "Folder of part-<i>.simplified.mfp (simplify --parts-dir)")->required();
  cmd->add_option("-o,--output", args->out, "Output mesh")->required();
  cmd->add_option("--max-error", args->max_error, "Maximum RMS error, % of the input's diagonal")->required();
  cmd->callback([args, &exit_status] {
    if (args->max_error <= 0) throw InvalidInput("--max-error must be > 0 (% of the diagonal)");
    std::size_t parts = 0;
    double diagonal = 0;
    read_partition_info(args->parts_dir, parts, diagonal);
    parallel::DistributedParams params;
    params.max_error = args->max_error / 100.0 * diagonal;
    params.progress = terminal_progress();
    parallel::DistributedReport report;
    mesh::Mesh output = parallel::merge_part_files(args->parts_dir, parts, params, report);
    if (params.progress) std::fprintf(stderr, "\n");
    mesh::write_mesh(output, args->out);
    std::printf("%s: %zu vertices, %zu triangles\n", args->out.c_str(), output.positions.size(), output.triangles.size());
    exit_status = 0;
  });
}

// The worker process of `simplify`: one part file in, its simplified part file out.
void add_part_simplify_command(CLI::App& app, int& exit_status) {
  auto dir = std::make_shared<std::string>();
  auto part = std::make_shared<std::size_t>(0);
  auto max_error = std::make_shared<double>(0);
  CLI::App* cmd = app.add_subcommand("part-simplify", "Worker of simplify: DIR/part-P.mfp -> DIR/part-P.simplified.mfp");
  cmd->add_option("DIR", *dir, "Parts directory")->required();
  cmd->add_option("P", *part, "Part number")->required();
  cmd->add_option("--max-error-abs", *max_error, "Maximum RMS error, absolute")->required();
  cmd->callback([dir, part, max_error, &exit_status] {
    if (*max_error <= 0) throw InvalidInput("--max-error-abs must be > 0");
    parallel::simplify_one_part(*dir, *part, *max_error);
    exit_status = 0;
  });
}

}  // namespace

MESHFLOW_COMMAND(part_simplify, add_part_simplify_command);
MESHFLOW_COMMAND(simplify, add_simplify_command);
MESHFLOW_COMMAND(partition, add_partition_command);
MESHFLOW_COMMAND(merge, add_merge_command);

}  // namespace meshflow::apps
