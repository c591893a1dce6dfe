#pragma once
// `meshflow up` runs its nodes as supervised child processes: each is `meshflow node`
// registering with the in-process hub; one that dies is started again; stop() sends SIGTERM,
// waits, and kills what is left.

#include <sys/types.h>

#include <atomic>
#include <filesystem>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

namespace meshflow::web {

struct SupervisedNode {
  std::vector<std::string> argv;
  pid_t pid = -1;
  int restarts = 0;
};

class NodeSupervisor {
 public:
  // `executable` is this program (/proc/self/exe); each node gets DATA/nodes/<i>.
  NodeSupervisor(std::string executable, std::string hub_url, std::filesystem::path token_file,
                 std::filesystem::path data_dir, int count);
  ~NodeSupervisor();
  void start();
  void stop();  // SIGTERM, wait up to 10 s, then SIGKILL

 private:
  void spawn(SupervisedNode& node);
  void watch();
  std::mutex mutex_;
  std::vector<SupervisedNode> nodes_;
  std::atomic<bool> stopping_{false};
  std::thread watcher_;
};

}  // namespace meshflow::web
