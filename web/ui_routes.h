#pragma once
// The browser UI (DESIGN §8): the hub serves the bundled pages of web/ui from a folder the
// build fills next to the executable (<build>/ui), or from $MESHFLOW_UI_DIR.

#include <filesystem>

namespace httplib {
class Server;
}

namespace meshflow::web {

// $MESHFLOW_UI_DIR if set, else the folder `ui` beside the running executable.
std::filesystem::path default_ui_dir();

// Serves `dir` at "/" (index.html for "/"); API routes keep precedence because no file there
// is named like them. Without the folder, "/" answers 503 saying how to build the pages.
void add_ui_routes(httplib::Server& server, const std::filesystem::path& dir);

}  // namespace meshflow::web
