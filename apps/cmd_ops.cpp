// meshflow op NAME IN [-o OUT] [--param k=v ...] [--correction C.mfc]
// meshflow compare A B [--json] [--one-way]
// meshflow diff A B -o C.mfc        meshflow patch A C.mfc -o B
#include <cstdio>
#include <iostream>

#include "apps/command.h"
#include "mesh/canonical_ply.h"
#include "mesh/errors.h"
#include "mesh/measures.h"
#include "mesh/mesh_io.h"
#include "protocol/correction.h"
#include "protocol/diff.h"
#include "services/compare.h"
#include "services/operation.h"

namespace meshflow::apps {
namespace {

struct OpArgs {
  std::string name, in, out, correction;
  std::vector<std::string> params;
};

std::map<std::string, std::string> parse_params(const std::vector<std::string>& items) {
  std::map<std::string, std::string> out;
  for (const auto& item : items) {
    auto eq = item.find('=');
    if (eq == std::string::npos || eq == 0) throw InvalidInput("--param wants NAME=VALUE, got '" + item + "'");
    out[item.substr(0, eq)] = item.substr(eq + 1);
  }
  return out;
}

void write_correction(const mesh::Mesh& base, const mesh::Mesh& result, const protocol::EditList& edits,
                      const std::string& path) {
  auto bytes = protocol::encode_correction(base, mesh::mesh_sha256(base), mesh::mesh_sha256(result), edits);
  mesh::write_file_bytes(path, bytes);
}

int run_op(const OpArgs& args) {
  const services::OperationSpec& spec = services::find_operation(args.name);
  services::Params params = services::resolve_params(spec, parse_params(args.params));
  if (spec.kind == services::OperationKind::Atomic && args.out.empty())
    throw InvalidInput(spec.name + " makes a mesh: give -o OUT");
  mesh::Mesh input = mesh::read_mesh(args.in);
  if (spec.kind == services::OperationKind::Analysis) {
    double value = services::run_analysis(spec, input);
    switch (spec.value_type) {
      case mesh::ValueType::Natural: std::printf("%llu\n", static_cast<unsigned long long>(value)); break;
      case mesh::ValueType::Real: std::printf("%.9g\n", value); break;
      case mesh::ValueType::Boolean: std::printf("%s\n", value != 0 ? "true" : "false"); break;
    }
    return 0;
  }
  services::AtomicResult result = services::run_atomic(spec, input, params);
  mesh::write_mesh(result.output, args.out);
  if (!args.correction.empty()) write_correction(input, result.output, result.edits, args.correction);
  return 0;
}

void add_op_command(CLI::App& app, int& exit_status) {
  auto args = std::make_shared<OpArgs>();
  CLI::App* cmd = app.add_subcommand("op", "Run one operation in-process (analysis ones print their value)");
  cmd->add_option("NAME", args->name, "Operation name (DESIGN §5)")->required();
  cmd->add_option("IN", args->in, "Input mesh")->required();
  cmd->add_option("-o,--output", args->out, "Output mesh (atomic operations)");
  cmd->add_option("--param", args->params, "NAME=VALUE (repeatable)")
      ->allow_extra_args(false);
  cmd->add_option("--correction", args->correction, "Also write the correction (.mfc)");
  cmd->callback([args, &exit_status] { exit_status = run_op(*args); });
}

void add_compare_command(CLI::App& app, int& exit_status) {
  auto a = std::make_shared<std::string>(), b = std::make_shared<std::string>();
  auto json = std::make_shared<bool>(false), one_way = std::make_shared<bool>(false);
  CLI::App* cmd = app.add_subcommand("compare", "Metro-style distance between two meshes (% of A's diagonal)");
  cmd->add_option("A", *a, "Reference mesh")->required();
  cmd->add_option("B", *b, "Compared mesh")->required();
  cmd->add_flag("--json", *json, "Print one JSON object");
  cmd->add_flag("--one-way", *one_way,
                "A -> B only, A streamed from its file (never loaded): its vertices are the samples");
  cmd->callback([a, b, json, one_way, &exit_status] {
    services::CompareResult r = *one_way ? services::compare_one_way(*a, mesh::read_mesh(*b))
                                         : services::compare(mesh::read_mesh(*a), mesh::read_mesh(*b));
    if (*json) std::cout << r.to_json() << std::endl;
    else if (r.one_way) std::printf("mean A->B %.6g%%  max A->B %.6g%%  (of A's diagonal; %zu of A's vertices)\n", r.mean_ab, r.max_ab, r.samples_a);
    else std::printf("mean A->B %.6g%%  max A->B %.6g%%\nmean B->A %.6g%%  max B->A %.6g%%  (of A's diagonal)\n",
                     r.mean_ab, r.max_ab, r.mean_ba, r.max_ba);
    exit_status = 0;
  });
}

void add_diff_patch_commands(CLI::App& app, int& exit_status) {
  auto a = std::make_shared<std::string>(), b = std::make_shared<std::string>(),
       out = std::make_shared<std::string>();
  CLI::App* diff = app.add_subcommand("diff", "Write the correction that turns A into B");
  diff->add_option("A", *a, "Base mesh")->required();
  diff->add_option("B", *b, "Result mesh")->required();
  diff->add_option("-o,--output", *out, "Correction file (.mfc)")->required();
  diff->callback([a, b, out, &exit_status] {
    mesh::Mesh base = mesh::read_mesh(*a), result = mesh::read_mesh(*b);
    write_correction(base, result, protocol::diff_meshes(base, result), *out);
    exit_status = 0;
  });
  auto pa = std::make_shared<std::string>(), pc = std::make_shared<std::string>(),
       pout = std::make_shared<std::string>();
  CLI::App* patch = app.add_subcommand("patch", "Apply a correction to A (hashes checked)");
  patch->add_option("A", *pa, "Base mesh")->required();
  patch->add_option("C", *pc, "Correction file (.mfc)")->required();
  patch->add_option("-o,--output", *pout, "Corrected mesh")->required();
  patch->callback([pa, pc, pout, &exit_status] {
    mesh::Mesh base = mesh::read_mesh(*pa);
    auto bytes = mesh::read_file_bytes(*pc);
    mesh::write_mesh(protocol::apply_correction(base, bytes), *pout);
    exit_status = 0;
  });
}

}  // namespace

MESHFLOW_COMMAND(op, add_op_command);
MESHFLOW_COMMAND(compare, add_compare_command);
MESHFLOW_COMMAND(diff, add_diff_patch_commands);

}  // namespace meshflow::apps
