#include "engine/executor.h"

#include <deque>
#include <map>

#include "mesh/errors.h"

namespace meshflow::engine {

void execute(const ValidatedWorkflow& workflow, NodeClient& nodes, const ExecutorOptions& options) {
  std::deque<const Task*> active;
  for (const Task& task : workflow.workflow->body) active.push_back(&task);
  std::map<const Task*, int> rounds;
  auto push_front_body = [&](const Body& body) {
    for (auto it = body.rbegin(); it != body.rend(); ++it) active.push_front(&*it);
  };
  while (!active.empty()) {
    if (options.cancelled && options.cancelled()) throw std::runtime_error("cancelled");
    const Task* task = active.front();
    active.pop_front();
    if (task->kind == Task::Kind::Atomic) {
      StepReport report = nodes.run_atomic(task->name, workflow.params.at(task));
      if (options.on_step) options.on_step(report);
      continue;
    }
    StepReport report = nodes.run_analysis(task->condition.analysis);
    if (options.on_step) options.on_step(report);
    bool holds = compare_values(report.value, task->condition.op, workflow.condition_values.at(task));
    if (task->kind == Task::Kind::If) {
      push_front_body(holds ? task->body : task->else_body);
    } else if (holds) {
      if (++rounds[task] > options.max_loop_iterations)
        throw InvalidInput("the <while> loop at line " + std::to_string(task->at.line) + " ran " +
                           std::to_string(options.max_loop_iterations) +
                           " times and its condition still holds (raise the bound with --max-loop)");
      active.push_front(task);
      push_front_body(task->body);
    }
  }
}

}  // namespace meshflow::engine
