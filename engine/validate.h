#pragma once
// Checks a parsed workflow against the operations available (DESIGN §5): known names, atomic
// vs analysis where each is used, parameters (all positional or all named; names, types,
// ranges), the operator allowed for the analysis's value type (booleans: EQ/NEQ), and a value of
// that type. Positional parameters are resolved to names.

#include <map>
#include <string>
#include <vector>

#include "engine/workflow.h"
#include "services/operation.h"

namespace meshflow::engine {

// Resolved parameters of every atomic task, keyed by the task's address in the workflow.
struct ValidatedWorkflow {
  const Workflow* workflow = nullptr;
  std::map<const Task*, services::Params> params;
  std::map<const Task*, double> condition_values;  // booleans as 0/1
};

// \throws ParseError naming `name`, the line and column of the offending element, and why.
ValidatedWorkflow validate_workflow(const Workflow& workflow, const std::string& name,
                                    const std::vector<services::OperationSpec>& available);

// The comparison of a condition (value types: natural and real numerically, booleans as 0/1).
bool compare_values(double measured, const std::string& op, double value);

}  // namespace meshflow::engine
