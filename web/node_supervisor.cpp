#include "web/node_supervisor.h"

#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>

#include "mesh/errors.h"

namespace meshflow::web {

NodeSupervisor::NodeSupervisor(std::string executable, std::string hub_url,
                               std::filesystem::path token_file, std::filesystem::path data_dir,
                               int count) {
  for (int i = 0; i < count; ++i) {
    std::filesystem::path dir = data_dir / "nodes" / std::to_string(i);
    std::filesystem::create_directories(dir);
    nodes_.push_back(SupervisedNode{{executable, "node", "--hub", hub_url, "--token-file",
                                     token_file.string(), "--data", dir.string(), "--listen",
                                     "127.0.0.1:0"}});
  }
}

NodeSupervisor::~NodeSupervisor() { stop(); }

void NodeSupervisor::spawn(SupervisedNode& node) {
  std::vector<char*> argv;
  for (auto& arg : node.argv) argv.push_back(arg.data());
  argv.push_back(nullptr);
  pid_t pid = fork();
  if (pid < 0) throw IoError("cannot start a node process");
  if (pid == 0) {
    // The child: its own signal mask (the parent blocks SIGTERM for sigwait), stdout quiet.
    sigset_t none;
    sigemptyset(&none);
    sigprocmask(SIG_SETMASK, &none, nullptr);
    std::freopen("/dev/null", "w", stdout);
    execv(argv[0], argv.data());
    _exit(127);
  }
  node.pid = pid;
}

void NodeSupervisor::start() {
  std::lock_guard lock(mutex_);
  for (auto& node : nodes_) spawn(node);
  watcher_ = std::thread([this] { watch(); });
}

void NodeSupervisor::watch() {
  while (!stopping_) {
    std::this_thread::sleep_for(std::chrono::milliseconds(200));
    std::lock_guard lock(mutex_);
    for (auto& node : nodes_) {
      if (node.pid <= 0 || stopping_) continue;
      int status = 0;
      if (waitpid(node.pid, &status, WNOHANG) == node.pid) {
        std::fprintf(stderr, "meshflow: node process %d exited (status %d); starting it again\n",
                     node.pid, status);
        node.pid = -1;
        node.restarts++;
        spawn(node);
      }
    }
  }
}

void NodeSupervisor::stop() {
  if (stopping_.exchange(true)) return;
  if (watcher_.joinable()) watcher_.join();
  std::lock_guard lock(mutex_);
  for (auto& node : nodes_)
    if (node.pid > 0) kill(node.pid, SIGTERM);
  auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(10);
  for (auto& node : nodes_) {
    while (node.pid > 0) {
      int status = 0;
      pid_t done = waitpid(node.pid, &status, WNOHANG);
      if (done == node.pid || done < 0) {
        node.pid = -1;
        break;
      }
      if (std::chrono::steady_clock::now() > deadline) {
        kill(node.pid, SIGKILL);
        waitpid(node.pid, &status, 0);
        node.pid = -1;
        break;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
    }
  }
}

}  // namespace meshflow::web
