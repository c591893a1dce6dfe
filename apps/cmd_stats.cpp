// meshflow stats FILE [--json]   and   meshflow convert IN OUT
#include <cstdio>
#include <iostream>

#include "apps/command.h"
#include "mesh/canonical_copy.h"
#include "mesh/measures.h"
#include "mesh/mesh_io.h"

namespace meshflow::apps {
namespace {

void print_table(const std::string& path, const mesh::ReadInfo& info, const mesh::Measures& m) {
  std::printf("%s: %s%s, compression %s", path.c_str(), mesh::to_string(info.format),
              info.is_binary ? " (binary)" : "", mesh::to_string(info.compression));
  if (info.polygons) std::printf(", %llu polygons fan-triangulated", (unsigned long long)info.polygons);
  std::printf("\n");
  for (const auto& field : mesh::kMeasureFields) {
    double value = mesh::measure_value(m, field.name);
    switch (field.type) {
      case mesh::ValueType::Natural: std::printf("  %-26s %llu\n", field.name, (unsigned long long)value); break;
      case mesh::ValueType::Real: std::printf("  %-26s %.9g\n", field.name, value); break;
      case mesh::ValueType::Boolean: std::printf("  %-26s %s\n", field.name, value != 0 ? "true" : "false"); break;
    }
  }
  std::printf("  details: %llu boundary edges, %llu non-manifold edges, %llu non-manifold vertices,\n"
              "           %llu inconsistently oriented edges, %llu degenerate triangles, %llu unreferenced vertices\n",
              (unsigned long long)m.boundary_edges, (unsigned long long)m.non_manifold_edges,
              (unsigned long long)m.non_manifold_vertices, (unsigned long long)m.inconsistent_edges,
              (unsigned long long)m.degenerate_triangles, (unsigned long long)m.unreferenced_vertices);
}

void add_stats_command(CLI::App& app, int& exit_status) {
  auto path = std::make_shared<std::string>();
  auto json = std::make_shared<bool>(false);
  CLI::App* cmd = app.add_subcommand("stats", "Print every analysis measure of a mesh");
  cmd->add_option("FILE", *path, "Mesh file (PLY, OFF, OBJ, STL; .gz/.zst too)")->required();
  cmd->add_flag("--json", *json, "One JSON object keyed by the analysis operation names");
  cmd->callback([path, json, &exit_status] {
    mesh::ReadInfo info;
    mesh::Mesh m = mesh::read_mesh(*path, &info);
    mesh::Measures measures = mesh::compute_measures(m);
    if (*json) std::cout << mesh::measures_to_json(measures) << std::endl;
    else print_table(*path, info, measures);
    exit_status = 0;
  });
}

void add_convert_command(CLI::App& app, int& exit_status) {
  auto in = std::make_shared<std::string>();
  auto out = std::make_shared<std::string>();
  CLI::App* cmd = app.add_subcommand("convert", "Convert a mesh between formats (by OUT's extension)");
  cmd->add_option("IN", *in, "Input mesh")->required();
  cmd->add_option("OUT", *out, "Output: .ply (canonical binary), .off, .obj, .stl, + .gz/.zst")->required();
  cmd->callback([in, out, &exit_status] {
    // To canonical PLY the mesh streams through two scratch files beside OUT (memory stays
    // a few MB whatever the input's size); other formats are written from the loaded mesh.
    if (mesh::is_canonical_ply_path(*out)) mesh::copy_canonical_ply(*in, *out);
    else mesh::write_mesh(mesh::read_mesh(*in), *out);
    exit_status = 0;
  });
}

}  // namespace

MESHFLOW_COMMAND(stats, add_stats_command);
MESHFLOW_COMMAND(convert, add_convert_command);

}  // namespace meshflow::apps
