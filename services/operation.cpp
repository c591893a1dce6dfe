#include "services/operation.h"

#include <charconv>
#include <cstdio>
#include <cmath>
#include <nlohmann/json.hpp>

#include "mesh/errors.h"
#include "protocol/diff.h"
#include "protocol/edit_mesh.h"
#include "services/repair.h"
#include "services/simplify.h"

namespace meshflow::services {
namespace {

const char* kDistanceUnit = "% of diagonal";
// Naturals travel as doubles: beyond 2^53 they would not be exact.
constexpr double kMaxExactNatural = 9007199254740992.0;
constexpr double kMaxVertexId = 4294967295.0;  // 32-bit vertex ids

// A bound as written in a message: "1", "100", "9007199254740992".
std::string number_text(double value) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.17g", value);
  return buffer;
}

std::vector<OperationSpec> build_specs() {
  std::vector<OperationSpec> specs = {
      {"RemoveSmallestComponents", OperationKind::Atomic, mesh::ValueType::Real, {},
       "Keeps the largest connected component (by triangle count) and removes the rest."},
      {"RemoveDegenerateTriangles", OperationKind::Atomic, mesh::ValueType::Real, {},
       "Removes zero-area and duplicate triangles by local edits (edge collapse, edge flip), "
       "decided with exact predicates, without opening holes."},
      {"AddNoise", OperationKind::Atomic, mesh::ValueType::Real,
       {{"maxDistance", ParamType::Real, 0.1, 0.0, 100.0, true, kDistanceUnit,
         "Largest displacement along the normal"},
        {"seed", ParamType::Natural, 0, 0.0, kMaxExactNatural, false, "", "Random seed (same seed, same noise)"}},
       "Moves each vertex along its normal by a uniform random distance up to maxDistance."},
      {"LaplacianSmoothing", OperationKind::Atomic, mesh::ValueType::Real,
       {{"iterations", ParamType::Natural, 1, 1.0, 10000.0, false, "", "Number of smoothing steps"}},
       "Uniform umbrella smoothing: interior vertices move to the average of their neighbours; "
       "boundary vertices stay."},
      {"FillHoles", OperationKind::Atomic, mesh::ValueType::Real, {},
       "Patches every boundary loop (Liepa: triangulate, refine, fair)."},
      {"FillHolesHeightField", OperationKind::Atomic, mesh::ValueType::Real, {},
       "Patches every boundary loop but the one with the most edges (the border of a height field)."},
      {"Simplify", OperationKind::Atomic, mesh::ValueType::Real,
       {{"maxError", ParamType::Real, 0.1, 0.0, 100.0, true, kDistanceUnit,
         "Keep the RMS distance of each new vertex to its planes within this (and larger patches within proportionally less)"},
        {"targetVertices", ParamType::Natural, 0, 0.0, kMaxVertexId, false, "vertices",
         "Stop at this many vertices instead (0: use maxError)"}},
       "Quadric edge collapse with optimal placement and an adaptive error stop."},
  };
  const char* descriptions[] = {
      "Number of vertices as stored.",
      "Number of triangles.",
      "Number of distinct edges.",
      "Number of boundary loops (connected components of the boundary edges).",
      "Number of connected components (triangles sharing vertices).",
      "Smallest triangle angle, in degrees.",
      "Largest triangle angle, in degrees.",
      "Average length of the edges.",
      "Total area of the triangles.",
      "Signed enclosed volume (positive for outward faces).",
      "Mean angle in degrees between the normals of adjacent triangles (noise).",
      "True when every edge has at most two triangles and every vertex one fan.",
      "True when adjacent triangles are consistently oriented.",
      "True when a consistent orientation exists.",
      "True when closed (no boundary) and manifold.",
  };
  int i = 0;
  for (const auto& field : mesh::kMeasureFields)
    specs.push_back({field.name, OperationKind::Analysis, field.type, {}, descriptions[i++]});
  return specs;
}

const char* type_name(ParamType t) {
  switch (t) {
    case ParamType::Natural: return "natural";
    case ParamType::Integer: return "integer";
    case ParamType::Real: return "real";
    case ParamType::Boolean: return "boolean";
  }
  return "real";
}

const char* value_type_name(mesh::ValueType t) {
  switch (t) {
    case mesh::ValueType::Natural: return "natural";
    case mesh::ValueType::Real: return "real";
    case mesh::ValueType::Boolean: return "boolean";
  }
  return "real";
}

double parse_value(const OperationSpec& op, const ParamSpec& p, const std::string& text) {
  auto fail = [&](const std::string& why) -> double {
    throw InvalidInput(op.name + ": parameter " + p.name + "=" + text + ": " + why);
  };
  if (p.type == ParamType::Boolean) {
    if (text == "true" || text == "1") return 1;
    if (text == "false" || text == "0") return 0;
    return fail("expected true or false");
  }
  double value = 0;
  const char* begin = text.data();
  const char* end = begin + text.size();
  auto [ptr, ec] = std::from_chars(begin, end, value);
  if (ec != std::errc() || ptr != end || !std::isfinite(value)) return fail(std::string("expected a ") + type_name(p.type) + " number");
  if ((p.type == ParamType::Natural || p.type == ParamType::Integer) && value != std::floor(value))
    return fail(std::string("expected a whole number"));
  if (p.min && (p.min_exclusive ? value <= *p.min : value < *p.min))
    return fail("must be " + std::string(p.min_exclusive ? "> " : ">= ") + number_text(*p.min));
  if (p.max && value > *p.max) return fail("must be <= " + number_text(*p.max));
  return value;
}

}  // namespace

const std::vector<OperationSpec>& operation_specs() {
  static const std::vector<OperationSpec> specs = build_specs();
  return specs;
}

const OperationSpec& find_operation(std::string_view name) {
  for (const auto& spec : operation_specs())
    if (spec.name == name) return spec;
  std::string known;
  for (const auto& spec : operation_specs()) known += (known.empty() ? "" : ", ") + spec.name;
  throw InvalidInput("unknown operation '" + std::string(name) + "' (known: " + known + ")");
}

Params resolve_params(const OperationSpec& spec, const std::map<std::string, std::string>& given) {
  Params params;
  for (const auto& entry : given) {
    const std::string& name = entry.first;  // (clang 14 cannot capture structured bindings)
    const std::string& text = entry.second;
    auto it = std::find_if(spec.params.begin(), spec.params.end(), [&](const ParamSpec& p) { return p.name == name; });
    if (it == spec.params.end()) {
      std::string known;
      for (const auto& p : spec.params) known += (known.empty() ? "" : ", ") + p.name;
      throw InvalidInput(spec.name + " has no parameter '" + name + "' (" +
                         (known.empty() ? std::string("it takes none") : "known: " + known) + ")");
    }
    params[name] = parse_value(spec, *it, text);
  }
  for (const auto& p : spec.params)
    if (!params.count(p.name)) params[p.name] = p.default_value;
  return params;
}

AtomicResult run_atomic(const OperationSpec& spec, const mesh::Mesh& input, const Params& params,
                        const RunContext& context) {
  if (spec.kind != OperationKind::Atomic) throw InvalidInput(spec.name + " is an analysis operation, not an atomic one");
  double diagonal = context.reference_diagonal > 0 ? context.reference_diagonal : mesh::bounding_box(input).diagonal();
  auto percent = [&](const char* name) { return params.at(name) / 100.0 * diagonal; };
  AtomicResult result;
  if (spec.name == "Simplify") {
    SimplifyParams sp;
    sp.target_vertices = static_cast<std::size_t>(params.at("targetVertices"));
    sp.max_error = sp.target_vertices ? 0 : percent("maxError");
    sp.progress = context.progress;
    sp.cancel = context.cancel;
    result.output = simplify(input, sp).output;
    result.edits = protocol::diff_meshes(input, result.output);
    result.edits_streamed = false;
    return result;
  }
  protocol::EditMesh m(input);
  if (spec.name == "RemoveSmallestComponents") remove_smallest_components(m);
  else if (spec.name == "RemoveDegenerateTriangles") remove_degenerate_triangles(m);
  else if (spec.name == "AddNoise") add_noise(m, percent("maxDistance"), static_cast<std::uint64_t>(params.at("seed")));
  else if (spec.name == "LaplacianSmoothing") laplacian_smoothing(m, static_cast<int>(params.at("iterations")), context.cancel);
  else if (spec.name == "FillHoles") fill_holes(m, false);
  else if (spec.name == "FillHolesHeightField") fill_holes(m, true);
  else throw InvalidInput("operation " + spec.name + " has no implementation");
  result.output = m.compact();
  result.edits = m.take_edits();
  return result;
}

double run_analysis(const OperationSpec& spec, const mesh::Mesh& input) {
  if (spec.kind != OperationKind::Analysis) throw InvalidInput(spec.name + " is an atomic operation, not an analysis one");
  return mesh::measure_value(mesh::compute_measures(input), spec.name);
}

nlohmann::json operations_to_json() {
  nlohmann::json out = nlohmann::json::array();
  for (const auto& spec : operation_specs()) {
    nlohmann::json op{{"name", spec.name},
                      {"kind", spec.kind == OperationKind::Atomic ? "atomic" : "analysis"},
                      {"description", spec.description}};
    if (spec.kind == OperationKind::Analysis) op["value_type"] = value_type_name(spec.value_type);
    nlohmann::json params = nlohmann::json::array();
    for (const auto& p : spec.params) {
      nlohmann::json param{{"name", p.name}, {"type", type_name(p.type)}, {"default", p.default_value},
                           {"unit", p.unit}, {"description", p.description}};
      if (p.min) param["min"] = *p.min, param["min_exclusive"] = p.min_exclusive;
      if (p.max) param["max"] = *p.max;
      params.push_back(param);
    }
    op["params"] = params;
    out.push_back(op);
  }
  return out;
}

}  // namespace meshflow::services
