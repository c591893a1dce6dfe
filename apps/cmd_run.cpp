// meshflow run WORKFLOW.xml INPUT -o OUTPUT [--max-loop N] [--hub URL [--transfer smaller|output]]
#include <csignal>
#include <cstdio>
#include <ctime>

#include "apps/command.h"
#include "apps/signals.h"
#include "engine/executor.h"
#include "engine/in_process_node.h"
#include "engine/remote_job.h"
#include "engine/workflow_parser.h"
#include "mesh/errors.h"
#include "mesh/mesh_io.h"

namespace meshflow::apps {
namespace {

struct RunArgs {
  std::string workflow, input, output, hub;
  int max_loop = 100;
  std::string transfer = "smaller";
};

// One line per step on standard error, the same in-process and through a hub.
void print_step(int index, const engine::StepReport& r) {
  std::string where = r.node == "in-process" ? "" : " on " + r.node;
  if (r.is_analysis) {
    std::fprintf(stderr, "step %d: %s = %g%s (%lld ms)\n", index, r.operation.c_str(), r.value, where.c_str(),
                 static_cast<long long>(r.run_ms));
    return;
  }
  std::fprintf(stderr, "step %d: %s%s (%lld ms)", index, r.operation.c_str(), where.c_str(),
               static_cast<long long>(r.run_ms));
  if (!r.sent.empty())
    std::fprintf(stderr, "; sent the %s (correction %llu B, output %llu B) in %lld ms, applied in %lld ms",
                 r.sent.c_str(), static_cast<unsigned long long>(r.correction_bytes),
                 static_cast<unsigned long long>(r.output_bytes), static_cast<long long>(r.transfer_ms),
                 static_cast<long long>(r.update_ms));
  std::fprintf(stderr, "\n");
}

int run_in_process(const RunArgs& args) {
  engine::Workflow workflow = engine::parse_workflow_file(args.workflow);
  engine::ValidatedWorkflow valid = engine::validate_workflow(workflow, args.workflow, services::operation_specs());
  engine::InProcessNode node(mesh::read_mesh(args.input));
  engine::ExecutorOptions options;
  options.max_loop_iterations = args.max_loop;
  int step = 0;
  options.on_step = [&](const engine::StepReport& r) { print_step(++step, r); };
  engine::execute(valid, node, options);
  mesh::write_mesh(node.current(), args.output);
  return 0;
}

// Through a hub: the workflow is validated there (errors come back with line and column);
// SIGINT or SIGTERM cancels the job on the hub.
int run_on_hub(const RunArgs& args) {
  if (args.max_loop != 100) throw InvalidInput("--max-loop applies to in-process runs; the hub sets its own bound");
  block_stop_signals();
  sigset_t stop = stop_signals();
  engine::RemoteJobOptions options;
  options.transfer = args.transfer;
  int step = 0;
  options.on_step = [&](const engine::StepReport& r) { print_step(++step, r); };
  options.on_submitted = [](const std::string& url) { std::fprintf(stderr, "job %s\n", url.c_str()); };
  options.interrupted = [&stop] {
    timespec now{0, 0};
    return sigtimedwait(&stop, nullptr, &now) > 0;
  };
  try {
    engine::RemoteJobResult result = engine::run_on_hub(args.hub, args.workflow, args.input, args.output, options);
    std::fprintf(stderr, "done in %lld ms; output %s (SHA-256 %s)\n", static_cast<long long>(result.elapsed_ms),
                 args.output.c_str(), result.output_sha256.c_str());
  } catch (const std::runtime_error& e) {
    if (std::string(e.what()) != "cancelled") throw;
    std::fprintf(stderr, "meshflow: interrupted; the job was cancelled on the hub\n");
    return 1;
  }
  return 0;
}

void add_run_command(CLI::App& app, int& exit_status) {
  auto args = std::make_shared<RunArgs>();
  CLI::App* cmd = app.add_subcommand("run", "Run a workflow on a mesh (in-process, or through a hub)");
  cmd->add_option("WORKFLOW", args->workflow, "Workflow XML file")->required();
  cmd->add_option("INPUT", args->input, "Input mesh")->required();
  cmd->add_option("-o,--output", args->output, "Output mesh")->required();
  cmd->add_option("--max-loop", args->max_loop, "Bound on the iterations of each while loop (in-process)");
  cmd->add_option("--hub", args->hub, "Run as a job on this hub and its nodes (e.g. http://127.0.0.1:8080)");
  cmd->add_option("--transfer", args->transfer,
                  "With --hub: what later nodes receive after each step: 'smaller' (the correction or the "
                  "output, whichever is smaller) or 'output' (always the whole mesh)")
      ->check(CLI::IsMember({"smaller", "output"}));
  cmd->callback([args, &exit_status] {
    exit_status = args->hub.empty() ? run_in_process(*args) : run_on_hub(*args);
  });
}

}  // namespace

MESHFLOW_COMMAND(run, add_run_command);

}  // namespace meshflow::apps
