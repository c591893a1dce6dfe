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

// What POST /api/jobs asks for.
struct JobRequest {
  std::string id;                  // from new_id(); DATA/jobs/ID holds the job's files
  std::string workflow_xml;
  std::string workflow_id;         // when run from the repository
  std::filesystem::path upload;    // the uploaded mesh (any format), or empty
  std::string input_url;           // else the hub fetches this (else the workflow's <input>)
  std::string transfer;            // "smaller" or "output" (always the whole mesh); "": the hub's default
};

class JobManager {
 public:
  JobManager(std::filesystem::path data_dir, ServiceRegistry& services, std::string token, int workers = 2);
  ~JobManager();

  // Starts running jobs (queued ones and those a previous hub left unfinished); nodes fetch
  // inputs from `hub_url`.
  void start(std::string hub_url);
  // input_url fetches: loopback and private addresses only when allowed (DESIGN §3), and at
  // most `max_bytes`.
  void set_fetch_policy(bool allow_private, std::uint64_t max_bytes) {
    allow_private_fetch_ = allow_private;
    max_fetch_bytes_ = max_bytes;
  }
  // The bound on each while loop's iterations (a job past it fails with a clear error).
  void set_max_loop_iterations(int bound) { max_loop_iterations_ = bound; }
  // What jobs that do not say use: "smaller" (the protocol) or "output" (whole meshes).
  void set_default_transfer(std::string mode) { default_transfer_ = std::move(mode); }

  // Validates the workflow (XSD + operations) and the input: an uploaded mesh is streamed into
  // its canonical copy DATA/jobs/ID/input.ply.zst now (mesh::copy_canonical_ply, never loaded);
  // an input URL is checked now (http(s), public unless allowed) and fetched and copied the
  // same way when the job starts. Journals the job and queues it.
  // \throws ParseError / InvalidInput for a bad workflow, mesh, URL or option (nothing is kept).
  std::string submit(const JobRequest& request);
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
  void fetch_input(engine::JobRecord& job);

  std::filesystem::path data_dir_;
  ServiceRegistry& services_;
  std::string token_;
  std::string hub_url_;
  bool allow_private_fetch_ = false;
  std::uint64_t max_fetch_bytes_ = 8ull << 30;
  int max_loop_iterations_ = 100;
  std::string default_transfer_ = "smaller";
  engine::JobJournal journal_;
  mutable std::mutex mutex_;
  std::condition_variable wake_;
  std::deque<std::string> queue_;
  std::map<std::string, std::shared_ptr<std::atomic<bool>>> cancel_;
  std::vector<std::thread> workers_;
  int worker_count_ = 2;
  bool stopping_ = false;
};

}  // namespace meshflow::web
