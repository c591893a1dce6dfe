#include "engine/validate.h"

#include <charconv>
#include <cmath>
#include <functional>

#include "mesh/errors.h"

namespace meshflow::engine {
namespace {

[[noreturn]] void fail(const std::string& name, Location at, const std::string& reason) {
  throw ParseError({name, static_cast<std::uint64_t>(at.line), static_cast<std::uint64_t>(at.column), {}}, reason);
}

const services::OperationSpec* find(const std::vector<services::OperationSpec>& ops, const std::string& n) {
  for (const auto& op : ops)
    if (op.name == n) return &op;
  return nullptr;
}

std::string known_names(const std::vector<services::OperationSpec>& ops, services::OperationKind kind) {
  std::string out;
  for (const auto& op : ops)
    if (op.kind == kind) out += (out.empty() ? "" : ", ") + op.name;
  return out;
}

}  // namespace

bool compare_values(double measured, const std::string& op, double value) {
  if (op == "EQ") return measured == value;
  if (op == "NEQ") return measured != value;
  if (op == "GT") return measured > value;
  if (op == "LT") return measured < value;
  if (op == "GEQ") return measured >= value;
  if (op == "LEQ") return measured <= value;
  throw InvalidInput("unknown operator '" + op + "'");
}

ValidatedWorkflow validate_workflow(const Workflow& workflow, const std::string& name,
                                    const std::vector<services::OperationSpec>& available) {
  ValidatedWorkflow out;
  out.workflow = &workflow;
  std::function<void(const Body&)> walk = [&](const Body& body) {
    for (const Task& task : body) {
      if (task.kind == Task::Kind::Atomic) {
        const services::OperationSpec* spec = find(available, task.name);
        if (!spec)
          fail(name, task.at, "<atomic> names unknown operation '" + task.name + "' (known: " +
                                  known_names(available, services::OperationKind::Atomic) + ")");
        if (spec->kind != services::OperationKind::Atomic)
          fail(name, task.at, "'" + task.name + "' is an analysis operation: use it in a <condition>");
        std::map<std::string, std::string> given;
        bool named = !task.parameters.empty() && task.parameters[0].name.has_value();
        for (std::size_t i = 0; i < task.parameters.size(); ++i) {
          const Parameter& p = task.parameters[i];
          if (p.name.has_value() != named)
            fail(name, p.at, "parameters of one <atomic> must be all positional or all named");
          std::string key;
          if (named) {
            key = *p.name;
          } else {
            if (i >= spec->params.size())
              fail(name, p.at, task.name + " takes " + std::to_string(spec->params.size()) +
                                   " parameter(s), this is number " + std::to_string(i + 1));
            key = spec->params[i].name;
          }
          if (given.count(key)) fail(name, p.at, "parameter '" + key + "' given twice");
          given[key] = p.value;
        }
        try {
          out.params[&task] = services::resolve_params(*spec, given);
        } catch (const InvalidInput& e) {
          fail(name, task.at, e.what());
        }
        continue;
      }
      const Condition& c = task.condition;
      const services::OperationSpec* spec = find(available, c.analysis);
      if (!spec)
        fail(name, c.at, "<analysis> names unknown operation '" + c.analysis + "' (known: " +
                             known_names(available, services::OperationKind::Analysis) + ")");
      if (spec->kind != services::OperationKind::Analysis)
        fail(name, c.at, "'" + c.analysis + "' is an atomic operation, not an analysis one");
      double value = spec->value_type == mesh::ValueType::Boolean ? 1 : 0;
      if (spec->value_type == mesh::ValueType::Boolean) {
        if (c.op != "EQ" && c.op != "NEQ")
          fail(name, c.at, c.analysis + " is boolean: only EQ and NEQ compare it, not " + c.op);
        if (c.value) {
          if (*c.value == "true") value = 1;
          else if (*c.value == "false") value = 0;
          else fail(name, c.at, c.analysis + " is boolean: expected true or false, found '" + *c.value + "'");
        }
      } else if (c.value) {
        const char* begin = c.value->data();
        const char* end = begin + c.value->size();
        auto [ptr, ec] = std::from_chars(begin, end, value);
        bool ok = ec == std::errc() && ptr == end;
        if (ok && spec->value_type == mesh::ValueType::Natural) ok = value >= 0 && value == std::floor(value);
        if (!ok)
          fail(name, c.at, c.analysis + " gives a " +
                               (spec->value_type == mesh::ValueType::Natural ? "natural" : "real") +
                               " number: '" + *c.value + "' is not one");
      }
      out.condition_values[&task] = value;
      walk(task.body);
      walk(task.else_body);
    }
  };
  walk(workflow.body);
  return out;
}

}  // namespace meshflow::engine
