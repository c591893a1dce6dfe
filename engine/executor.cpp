#include "engine/executor.h"

#include <algorithm>
#include <deque>
#include <map>

#include "mesh/errors.h"

namespace meshflow::engine {

namespace {

// The operations of the tasks still in the active list (bodies included: a while loop we are
// inside of sits in the list behind its copied body, so its operations count as later too).
std::vector<std::string> later_operations(const std::deque<const Task*>& active) {
  std::vector<std::string> out;
  auto add = [&](const std::string& name) {
    if (!name.empty() && std::find(out.begin(), out.end(), name) == out.end()) out.push_back(name);
  };
  auto walk = [&](auto& self, const Task& task) -> void {
    if (task.kind == Task::Kind::Atomic) return add(task.name);
    add(task.condition.analysis);
    for (const Task& t : task.body) self(self, t);
    for (const Task& t : task.else_body) self(self, t);
  };
  for (const Task* task : active) walk(walk, *task);
  return out;
}

}  // namespace

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
    nodes.expect_later(later_operations(active));
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
