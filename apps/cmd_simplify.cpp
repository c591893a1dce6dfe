// meshflow simplify IN -o OUT --max-error E [--workers N] [--vertices-per-part N] [--report R.json]
#include <unistd.h>

#include <cstdio>
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
};

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
  cmd->callback([args, &exit_status] {
    if (!args->node_urls.empty())
      throw InvalidInput("--node-urls: dispatch to mesh nodes is not implemented yet; use --workers");
    if (args->max_error <= 0) throw InvalidInput("--max-error must be > 0 (% of the diagonal)");
    mesh::Mesh input = mesh::read_mesh(args->in);
    parallel::DistributedParams params;
    params.max_error = args->max_error / 100.0 * mesh::bounding_box(input).diagonal();
    params.vertices_per_part = args->vertices_per_part;
    params.workers = args->workers ? args->workers : std::max(1u, std::thread::hardware_concurrency());
    if (isatty(STDERR_FILENO))
      params.progress = [](const std::string& step, double f) {
        int filled = static_cast<int>(30 * f);
        std::fprintf(stderr, "\r%-6s [%-30.*s] %5.1f%%", step.c_str(), filled, "##############################", 100 * f);
      };
    parallel::DistributedReport report;
    mesh::Mesh output = parallel::simplify_distributed(input, params, report);
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

}  // namespace

MESHFLOW_COMMAND(simplify, add_simplify_command);

}  // namespace meshflow::apps
