// meshflow run WORKFLOW.xml INPUT -o OUTPUT [--max-loop N]   (in-process; --hub comes with jobs)
#include <cstdio>

#include "apps/command.h"
#include "engine/executor.h"
#include "engine/in_process_node.h"
#include "engine/workflow_parser.h"
#include "mesh/errors.h"
#include "mesh/mesh_io.h"

namespace meshflow::apps {
namespace {

struct RunArgs {
  std::string workflow, input, output, hub;
  int max_loop = 100;
};

int run_workflow(const RunArgs& args) {
  engine::Workflow workflow = engine::parse_workflow_file(args.workflow);
  engine::ValidatedWorkflow valid = engine::validate_workflow(workflow, args.workflow, services::operation_specs());
  engine::InProcessNode node(mesh::read_mesh(args.input));
  engine::ExecutorOptions options;
  options.max_loop_iterations = args.max_loop;
  int step = 0;
  options.on_step = [&](const engine::StepReport& r) {
    if (r.is_analysis)
      std::fprintf(stderr, "step %d: %s = %g (%lld ms)\n", ++step, r.operation.c_str(), r.value, (long long)r.run_ms);
    else
      std::fprintf(stderr, "step %d: %s (%lld ms)\n", ++step, r.operation.c_str(), (long long)r.run_ms);
  };
  engine::execute(valid, node, options);
  mesh::write_mesh(node.current(), args.output);
  return 0;
}

void add_run_command(CLI::App& app, int& exit_status) {
  auto args = std::make_shared<RunArgs>();
  CLI::App* cmd = app.add_subcommand("run", "Run a workflow on a mesh (in-process)");
  cmd->add_option("WORKFLOW", args->workflow, "Workflow XML file")->required();
  cmd->add_option("INPUT", args->input, "Input mesh")->required();
  cmd->add_option("-o,--output", args->output, "Output mesh")->required();
  cmd->add_option("--max-loop", args->max_loop, "Bound on the iterations of each while loop");
  cmd->callback([args, &exit_status] { exit_status = run_workflow(*args); });
}

}  // namespace

MESHFLOW_COMMAND(run, add_run_command);

}  // namespace meshflow::apps
