#pragma once
// The hub's jobs (DESIGN §3): a workflow run on an input mesh over the registered nodes, in the
// background, journaled in SQLite (engine/job_journal.h) with per-step timings and transfer
// sizes; the hub keeps the canonical input (for the nodes) and the output (for the user).

#include <atomic>
#include <condition_variable>
#include <deque>
#include <filesystem>
#include <map>
#include <memory>
#include <mutex>
#include <nlohmann/json.hpp>
#include <string>
#include <thread>
#include <vector>

#include "engine/job_journal.h"
#include "web/service_registry.h"

namespace meshflow::web {

class JobManager {
 public:
  JobManager(std::filesystem::path data_dir, ServiceRegistry& services, std::string token, int workers = 2);
  ~JobManager();

  void set_hub_url(std::string url) { hub_url_ = std::move(url); }

  // Validates the workflow (XSD + operations) and the uploaded mesh (any format; canonicalised
  // to DATA/jobs/ID/input.ply.zst), journals the job and queues it. \throws ParseError /
  // InvalidInput for a bad workflow or mesh (nothing is kept then).
  std::string submit(const std::string& workflow_xml, const std::filesystem::path& upload);

  std::optional<nlohmann::json> status(const std::string& id) const;  // DESIGN §3 job JSON
  bool cancel(const std::string& id);
  std::filesystem::path input_file(const std::string& id) const;   // canonical PLY, zstd
  std::filesystem::path output_file(const std::string& id) const;  // canonical PLY
  std::filesystem::path job_dir(const std::string& id) const;
  std::string new_id();

 private:
  void worker();
  void run(const std::string& id);

  std::filesystem::path data_dir_;
  ServiceRegistry& services_;
  std::string token_;
  std::string hub_url_;
  engine::JobJournal journal_;
  mutable std::mutex mutex_;
  std::condition_variable wake_;
  std::deque<std::string> queue_;
  std::map<std::string, std::shared_ptr<std::atomic<bool>>> cancel_;
  std::vector<std::thread> workers_;
  bool stopping_ = false;
};

}  // namespace meshflow::web
