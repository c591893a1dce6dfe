#include "web/ui_routes.h"

#include <httplib.h>

#include <cstdlib>
#include <system_error>

namespace meshflow::web {

std::filesystem::path default_ui_dir() {
  if (const char* dir = std::getenv("MESHFLOW_UI_DIR"); dir && *dir) return dir;
  std::error_code error;
  auto exe = std::filesystem::read_symlink("/proc/self/exe", error);
  if (error) return "ui";
  return exe.parent_path() / "ui";
}

void add_ui_routes(httplib::Server& server, const std::filesystem::path& dir) {
  std::error_code error;
  if (std::filesystem::is_regular_file(dir / "index.html", error)) {
    server.set_file_extension_and_mimetype_mapping("mjs", "text/javascript");
    server.set_file_extension_and_mimetype_mapping("map", "application/json");
    server.set_mount_point("/", dir.string(), {{"Cache-Control", "no-cache"}});
    return;
  }
  std::string text = "The browser UI is not built: " + (dir / "index.html").string() +
                     " is missing (run `make build`, which bundles web/ui with npm and esbuild).\n";
  server.Get("/", [text](const httplib::Request&, httplib::Response& res) {
    res.status = 503;
    res.set_content(text, "text/plain");
  });
}

}  // namespace meshflow::web
