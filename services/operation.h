#pragma once
// The operations of DESIGN §5 as one registry: names, kinds, parameters (types, defaults,
// ranges, units), descriptions, and how to run them. The node server, the workflow engine's
// validation and `meshflow op` all read this one list.

#include <atomic>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <nlohmann/json_fwd.hpp>

#include "mesh/measures.h"
#include "mesh/mesh.h"
#include "protocol/edits.h"

namespace meshflow::services {

enum class OperationKind { Atomic, Analysis };
enum class ParamType { Natural, Integer, Real, Boolean };

struct ParamSpec {
  std::string name;
  ParamType type = ParamType::Real;
  double default_value = 0;
  std::optional<double> min, max;
  bool min_exclusive = false;
  std::string unit;  // "% of diagonal", "" ...
  std::string description;
};

struct OperationSpec {
  std::string name;
  OperationKind kind = OperationKind::Atomic;
  mesh::ValueType value_type = mesh::ValueType::Real;  // analysis operations
  std::vector<ParamSpec> params;
  std::string description;
};

const std::vector<OperationSpec>& operation_specs();

// \throws InvalidInput "unknown operation 'X' (known: ...)".
const OperationSpec& find_operation(std::string_view name);

using Params = std::map<std::string, double>;

// Validates the given parameters (names, types, ranges) and fills in defaults.
// \throws InvalidInput naming the parameter, the value and what was expected.
Params resolve_params(const OperationSpec& spec, const std::map<std::string, std::string>& given);

struct RunContext {
  double reference_diagonal = 0;  // distances are % of this; 0: the input's own diagonal
  std::function<void(double)> progress;
  const std::atomic<bool>* cancel = nullptr;
};

struct AtomicResult {
  mesh::Mesh output;
  protocol::EditList edits;  // apply_edits(input, edits) == output, bit for bit
  bool edits_streamed = true;  // false: computed by diffing input and output
};

// \throws InvalidInput when the operation is an analysis one or the input is unusable.
AtomicResult run_atomic(const OperationSpec& spec, const mesh::Mesh& input, const Params& params,
                        const RunContext& context = {});
double run_analysis(const OperationSpec& spec, const mesh::Mesh& input);

// [{name, kind, value_type?, params: [{name,type,default,min,max,unit,description}], description}]
nlohmann::json operations_to_json();

}  // namespace meshflow::services
