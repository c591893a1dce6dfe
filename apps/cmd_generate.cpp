// meshflow generate terrain|sphere --triangles N -o OUT.ply [--seed S]
#include <unistd.h>

#include <cstdio>

#include "apps/command.h"
#include "mesh/errors.h"
#include "mesh/generate.h"

namespace meshflow::apps {
namespace {

struct GenerateArgs {
  std::string shape;
  std::uint64_t triangles = 0;
  std::string out;
  std::uint64_t seed = 1;
};

void add_generate_command(CLI::App& app, int& exit_status) {
  auto args = std::make_shared<GenerateArgs>();
  CLI::App* cmd = app.add_subcommand("generate", "Stream a synthetic mesh of any size to disk");
  cmd->add_option("SHAPE", args->shape, "terrain (fractal height field) or sphere (closed, bumpy)")
      ->required()
      ->check(CLI::IsMember({"terrain", "sphere"}));
  cmd->add_option("--triangles", args->triangles, "Approximate number of triangles")->required();
  cmd->add_option("-o,--output", args->out, "Output file (canonical binary PLY)")->required();
  cmd->add_option("--seed", args->seed, "Noise seed");
  cmd->callback([args, &exit_status] {
    mesh::GenerateParams params;
    params.shape = args->shape == "sphere" ? mesh::Shape::Sphere : mesh::Shape::Terrain;
    params.triangles = args->triangles;
    params.seed = args->seed;
    bool tty = isatty(STDERR_FILENO);
    if (tty)
      params.progress = [](double f) { std::fprintf(stderr, "\rgenerating %5.1f%%", 100 * f); };
    mesh::GenerateResult r = mesh::generate_mesh(params, args->out);
    if (tty) std::fprintf(stderr, "\r                  \r");
    std::printf("%s: %llu vertices, %llu triangles\n", args->out.c_str(),
                (unsigned long long)r.vertices, (unsigned long long)r.triangles);
    exit_status = 0;
  });
}

}  // namespace

MESHFLOW_COMMAND(generate, add_generate_command);

}  // namespace meshflow::apps
