#pragma once
// The hub's job journal (DESIGN §3, §10): one SQLite database under the data directory with
// every job and every finished step, so a restarted hub continues each job from its last
// finished step and GET /api/jobs/{id} reports per-step timings and transfer sizes.

#include <cstdint>
#include <filesystem>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

struct sqlite3;

namespace meshflow::engine {

enum class JobState { Queued, Running, Done, Failed, Cancelled };
const char* to_string(JobState state);
JobState job_state_from_string(const std::string& text);

struct StepRecord {
  int seq = 0;                    // 0-based order of execution
  std::string operation;
  std::string kind;               // "atomic" or "analysis"
  std::string node;               // base URL, or "in-process"
  std::string state;              // "running", "done", "failed"
  std::int64_t run_ms = 0;
  std::int64_t wait_ms = 0;       // the node waiting for its input before running
  std::int64_t transfer_ms = 0;   // forwarding the result to later nodes
  std::int64_t update_ms = 0;     // applying corrections on later nodes
  std::string sent;               // "correction" or "output" (what later nodes received)
  std::uint64_t correction_bytes = 0;
  std::uint64_t output_bytes = 0;
  std::optional<double> value;    // analysis steps
  std::string output_sha256;      // atomic steps: the mesh after the step
  std::uint64_t output_vertices = 0;  // atomic steps: its vertex count (0: unknown)
  std::string output_url;
  std::string correction_url;
  std::string error;
};

struct JobRecord {
  std::string id;
  JobState state = JobState::Queued;
  std::string workflow_xml;
  std::string workflow_id;        // when run from the repository
  std::string input_path;         // the hub's canonical copy of the input ("" until fetched)
  std::string input_sha256;
  std::string input_url;          // where the hub fetches the input from, when not uploaded
  std::string transfer = "smaller";  // engine::TransferMode: "smaller" or "output"
  std::int64_t broadcast_ms = 0;  // the input broadcast (slowest node)
  std::uint64_t broadcast_bytes = 0;
  std::int64_t elapsed_ms = 0;    // wall time of the run, first step to output on the hub
  std::string output_path;        // the hub's copy of the result, when done
  std::string output_sha256;
  std::string error;
  std::string created;            // ISO 8601 UTC
  std::vector<StepRecord> steps;
};

class JobJournal {
 public:
  explicit JobJournal(const std::filesystem::path& file);
  ~JobJournal();
  JobJournal(const JobJournal&) = delete;
  JobJournal& operator=(const JobJournal&) = delete;

  void create(const JobRecord& job);
  void set_state(const std::string& id, JobState state, const std::string& error = {});
  void set_input(const std::string& id, const std::string& path, const std::string& sha256);
  void set_output(const std::string& id, const std::string& path, const std::string& sha256);
  void set_timings(const std::string& id, std::int64_t broadcast_ms, std::uint64_t broadcast_bytes,
                   std::int64_t elapsed_ms);
  void put_step(const std::string& id, const StepRecord& step);  // insert or replace by seq
  std::optional<JobRecord> get(const std::string& id) const;
  std::vector<std::string> unfinished() const;  // queued or running: to resume after a restart
  std::vector<JobRecord> recent(std::size_t limit) const;  // without steps

 private:
  sqlite3* db_ = nullptr;
  mutable std::mutex mutex_;
};

}  // namespace meshflow::engine
