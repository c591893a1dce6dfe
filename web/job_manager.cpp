#include "web/job_manager.h"

#include <openssl/rand.h>

#include <fstream>
#include <sstream>

#include "engine/executor.h"
#include "engine/http_node_client.h"
#include "engine/validate.h"
#include "engine/workflow_parser.h"
#include "mesh/canonical_copy.h"
#include "mesh/errors.h"
#include "mesh/mesh_io.h"
#include "protocol/http_client.h"
#include "services/operation.h"

namespace meshflow::web {

using nlohmann::json;

namespace {

// Resuming after a hub restart: the executor is deterministic given the steps' answers, so
// the steps the journal already holds are answered from it (the mesh after the last finished
// atomic step is still on the nodes) and the rest run live.
class ReplayingNodes : public engine::NodeClient {
 public:
  ReplayingNodes(std::vector<engine::StepRecord> done, engine::HttpNodeClient& live)
      : done_(std::move(done)), live_(live) {}
  engine::StepReport run_atomic(const std::string& operation, const services::Params& params) override {
    if (const engine::StepRecord* r = next(operation)) {
      if (!r->output_url.empty())
        live_.set_current(r->output_url, r->output_sha256, r->node, r->output_vertices);
      return report_of(*r);
    }
    return live_.run_atomic(operation, params);
  }
  engine::StepReport run_analysis(const std::string& operation) override {
    if (const engine::StepRecord* r = next(operation)) return report_of(*r);
    return live_.run_analysis(operation);
  }
  void expect_later(const std::vector<std::string>& operations) override { live_.expect_later(operations); }
  std::size_t replayed() const { return at_; }

 private:
  const engine::StepRecord* next(const std::string& operation) {
    if (at_ >= done_.size() || done_[at_].operation != operation) {
      at_ = done_.size();  // anything unexpected: run live from here
      return nullptr;
    }
    return &done_[at_++];
  }
  static engine::StepReport report_of(const engine::StepRecord& r) {
    engine::StepReport report;
    report.operation = r.operation;
    report.node = r.node;
    report.run_ms = r.run_ms;
    report.wait_ms = r.wait_ms;
    report.transfer_ms = r.transfer_ms;
    report.update_ms = r.update_ms;
    report.sent = r.sent;
    report.correction_bytes = r.correction_bytes;
    report.output_bytes = r.output_bytes;
    report.vertices = r.output_vertices;
    report.is_analysis = r.kind == "analysis";
    report.value = r.value.value_or(0);
    return report;
  }
  std::vector<engine::StepRecord> done_;
  engine::HttpNodeClient& live_;
  std::size_t at_ = 0;
};

}  // namespace

JobManager::JobManager(std::filesystem::path data_dir, ServiceRegistry& services, std::string token, int workers)
    : data_dir_(std::move(data_dir)), services_(services), token_(std::move(token)),
      journal_(data_dir_ / "jobs.sqlite") {
  std::filesystem::create_directories(data_dir_ / "jobs");
  // Jobs a previous hub left unfinished go on from their last finished step (run()).
  for (const auto& id : journal_.unfinished()) queue_.push_back(id), cancel_[id] = std::make_shared<std::atomic<bool>>(false);
  worker_count_ = workers;
}

void JobManager::start(std::string hub_url) {
  std::lock_guard lock(mutex_);
  hub_url_ = std::move(hub_url);
  if (!workers_.empty()) return;
  // Only now: a resumed job needs the URL nodes reach the hub at.
  for (int i = 0; i < worker_count_; ++i) workers_.emplace_back([this] { worker(); });
}

JobManager::~JobManager() {
  {
    std::lock_guard lock(mutex_);
    stopping_ = true;
    for (auto& [id, flag] : cancel_) *flag = true;
  }
  wake_.notify_all();
  for (auto& w : workers_) w.join();
}

std::string JobManager::new_id() {
  unsigned char bytes[8];
  RAND_bytes(bytes, sizeof bytes);
  static const char* hex = "0123456789abcdef";
  std::string id;
  for (unsigned char b : bytes) id += hex[b >> 4], id += hex[b & 15];
  return id;
}

std::filesystem::path JobManager::job_dir(const std::string& id) const { return data_dir_ / "jobs" / id; }
std::filesystem::path JobManager::input_file(const std::string& id) const { return job_dir(id) / "input.ply.zst"; }
std::filesystem::path JobManager::output_file(const std::string& id) const { return job_dir(id) / "output.ply"; }

std::string JobManager::submit(const std::string& workflow_xml, const std::filesystem::path& upload) {
  JobRequest request;
  request.id = upload.parent_path().filename().string();
  request.workflow_xml = workflow_xml;
  request.upload = upload;
  return submit(request);
}

std::string JobManager::submit(const JobRequest& request) {
  engine::Workflow workflow = engine::parse_workflow(request.workflow_xml, "workflow.xml");
  engine::validate_workflow(workflow, "workflow.xml", services::operation_specs());
  std::string transfer = request.transfer.empty() ? default_transfer_ : request.transfer;
  engine::transfer_mode_from_string(transfer);  // a clear 400 for a bad value
  const std::string& id = request.id;
  std::filesystem::create_directories(job_dir(id));
  engine::JobRecord job;
  job.id = id;
  job.workflow_xml = request.workflow_xml;
  job.workflow_id = request.workflow_id;
  job.transfer = transfer;
  if (!request.upload.empty()) {
    // Streamed (issue 7): the hub never holds the input mesh; bad input throws the reader's
    // ParseError, naming the file and the line or byte, and leaves no input file behind.
    mesh::CanonicalCopy copy = mesh::copy_canonical_ply(request.upload.string(), input_file(id).string());
    std::filesystem::remove(request.upload);
    job.input_path = input_file(id).string();
    job.input_sha256 = copy.sha256;
  } else {
    job.input_url = !request.input_url.empty() ? request.input_url : workflow.input_url.value_or("");
    if (job.input_url.empty())
      throw InvalidInput("no input mesh: give the field 'input' (a mesh file) or 'input_url', or name one in the "
                         "workflow's <input>");
    if (!allow_private_fetch_) {
      std::string why = protocol::why_not_public(job.input_url);
      if (!why.empty())
        throw InvalidInput("input_url " + job.input_url + ": " + why +
                           "; the hub fetches only public addresses unless started with --allow-private-fetch");
    } else if (job.input_url.rfind("http://", 0) != 0 && job.input_url.rfind("https://", 0) != 0) {
      throw InvalidInput("input_url must be an http or https URL, not " + job.input_url);
    }
  }
  journal_.create(job);
  {
    std::lock_guard lock(mutex_);
    cancel_[id] = std::make_shared<std::atomic<bool>>(false);
    queue_.push_back(id);
  }
  wake_.notify_one();
  return id;
}

void JobManager::worker() {
  for (;;) {
    std::string id;
    {
      std::unique_lock lock(mutex_);
      wake_.wait(lock, [&] { return stopping_ || !queue_.empty(); });
      if (stopping_) return;
      id = queue_.front();
      queue_.pop_front();
    }
    run(id);
  }
}

// The hub fetches a user's input_url itself (DESIGN §3) and keeps the canonical copy that the
// nodes download.
void JobManager::fetch_input(engine::JobRecord& job) {
  std::filesystem::path fetched = job_dir(job.id) / "fetched";
  protocol::HttpOptions http;
  http.timeout = std::chrono::minutes(30);
  http.public_only = !allow_private_fetch_;
  http.follow_redirects = true;
  http.max_bytes = max_fetch_bytes_;
  protocol::DownloadResult got = protocol::http_download(job.input_url, fetched.string(), std::nullopt, false, http);
  if (!got.ok()) throw IoError("fetching input_url " + job.input_url + ": " + got.describe());
  mesh::CanonicalCopy copy;
  try {
    copy = mesh::copy_canonical_ply(fetched.string(), input_file(job.id).string());
  } catch (const InvalidInput& e) {  // the reader's ParseError; a failed write is an IoError
    throw InvalidInput("input_url " + job.input_url + " is not a mesh: " + e.what());
  }
  std::filesystem::remove(fetched);
  job.input_path = input_file(job.id).string();
  job.input_sha256 = copy.sha256;
  journal_.set_input(job.id, job.input_path, job.input_sha256);
}

void JobManager::run(const std::string& id) {
  std::optional<engine::JobRecord> job = journal_.get(id);
  if (!job) return;
  std::shared_ptr<std::atomic<bool>> cancelled;
  {
    std::lock_guard lock(mutex_);
    cancelled = cancel_[id];
  }
  journal_.set_state(id, engine::JobState::Running);
  std::optional<engine::StepRecord> running;  // the step under way, for progress
  int seq = 0;
  try {
    if (job->input_path.empty()) fetch_input(*job);
    auto started = std::chrono::steady_clock::now();
    engine::Workflow workflow = engine::parse_workflow(job->workflow_xml, "workflow.xml");
    engine::ValidatedWorkflow valid = engine::validate_workflow(workflow, "workflow.xml", services::operation_specs());
    engine::HttpNodeOptions options;
    options.token = token_;
    options.candidates = [this](const std::string& op) { return services_.candidates(op); };
    options.load = [this](const std::string& node, int delta) { services_.adjust_load(node, delta); };
    options.measured = [this](const std::string& node, std::uint64_t bytes, std::int64_t ms) {
      services_.record_transfer(node, bytes, ms);
    };
    options.cancelled = [cancelled] { return cancelled->load(); };
    options.transfer = engine::transfer_mode_from_string(job->transfer);
    options.on_start = [&](const std::string& op, const std::string& node) {
      engine::StepRecord s;
      s.seq = seq;
      s.operation = op;
      s.kind = services::find_operation(op).kind == services::OperationKind::Analysis ? "analysis" : "atomic";
      s.node = node;
      s.state = "running";
      running = s;
      journal_.put_step(id, s);
    };
    // The canonical input streamed for its box and vertex count, never loaded (issue 7).
    mesh::MeshExtent input = mesh::measure_extent(job->input_path);
    options.reference_diagonal = input.diagonal();
    // A Simplify step too large for every node runs in parts; its output is served from here.
    options.input_vertices = input.vertices;
    options.work_dir = (job_dir(id) / "split").string();
    options.publish = [this, id](const std::string& path) {
      std::string relative = std::filesystem::relative(path, job_dir(id) / "split").generic_string();
      return hub_url_ + "/api/jobs/" + id + "/split/" + relative;
    };
    int last_percent = -1;
    std::mutex progress_mutex;  // the parts report from their dispatch threads
    options.progress = [&](const std::string& step, double fraction) {
      std::lock_guard lock(progress_mutex);
      int percent = static_cast<int>(fraction * 100);
      if (!running || percent / 5 == last_percent / 5) return;
      last_percent = percent;
      engine::StepRecord now = *running;
      now.node = running->node + " - " + step + " " + std::to_string(percent) + "%";
      journal_.put_step(id, now);
    };
    std::string input_url = hub_url_ + "/api/jobs/" + id + "/input";
    engine::HttpNodeClient live(options, input_url, job->input_sha256);
    live.plan(engine::operations_used(workflow));
    live.broadcast();
    std::vector<engine::StepRecord> done;
    for (const auto& s : job->steps)
      if (s.state == "done") done.push_back(s);
    ReplayingNodes nodes(done, live);
    engine::ExecutorOptions exec;
    exec.max_loop_iterations = max_loop_iterations_;
    exec.cancelled = [cancelled] { return cancelled->load(); };
    exec.on_step = [&](const engine::StepReport& r) {
      engine::StepRecord s;
      s.seq = seq++;
      s.operation = r.operation;
      s.kind = r.is_analysis ? "analysis" : "atomic";
      s.node = r.node;
      s.state = "done";
      s.run_ms = r.run_ms;
      s.wait_ms = r.wait_ms;
      s.transfer_ms = r.transfer_ms;
      s.update_ms = r.update_ms;
      s.sent = r.sent;
      s.correction_bytes = r.correction_bytes;
      s.output_bytes = r.output_bytes;
      if (r.is_analysis) s.value = r.value;
      s.output_sha256 = live.current_sha256();
      s.output_url = live.current_url();
      s.output_vertices = r.vertices;
      running.reset();
      journal_.put_step(id, s);
    };
    engine::execute(valid, nodes, exec);
    engine::BroadcastReport broadcast = live.broadcast_report();
    // The result travels once, to the hub, for the user.
    std::filesystem::path fetched = job_dir(id) / "output.ply.zst";
    protocol::HttpOptions http;
    http.timeout = std::chrono::minutes(30);
    auto fetching = std::chrono::steady_clock::now();
    protocol::DownloadResult got =
        protocol::http_download(live.current_url(), fetched.string(), live.current_sha256(), true, http);
    if (!got.ok()) throw IoError("fetching the result from " + live.current_url() + ": " + got.describe());
    if (!live.current_node().empty())
      services_.record_transfer(live.current_node(), got.bytes,
                                std::chrono::duration_cast<std::chrono::milliseconds>(
                                    std::chrono::steady_clock::now() - fetching).count());
    // The node's canonical PLY, zstd-compressed: decompressed by a streaming copy, whose hash
    // is the one the download was checked against.
    mesh::CanonicalCopy output = mesh::copy_canonical_ply(fetched.string(), output_file(id).string());
    std::filesystem::remove(fetched);
    if (output.sha256 != live.current_sha256()) {
      std::filesystem::remove(output_file(id));
      throw IoError("the result from " + live.current_url() + " is not canonical: its SHA-256 is " +
                    output.sha256 + ", expected " + live.current_sha256());
    }
    auto elapsed = std::chrono::duration_cast<std::chrono::milliseconds>(std::chrono::steady_clock::now() - started);
    journal_.set_timings(id, broadcast.ms, broadcast.bytes, elapsed.count());
    journal_.set_output(id, output_file(id).string(), live.current_sha256());
    journal_.set_state(id, engine::JobState::Done);
  } catch (const std::exception& e) {
    {
      std::lock_guard lock(mutex_);
      if (stopping_) return;  // the hub is shutting down: the job resumes when it restarts
    }
    bool was_cancelled = cancelled->load();
    if (running) {
      running->state = was_cancelled ? "cancelled" : "failed";
      running->error = e.what();
      journal_.put_step(id, *running);
    }
    journal_.set_state(id, was_cancelled ? engine::JobState::Cancelled : engine::JobState::Failed,
                       was_cancelled ? "cancelled" : e.what());
  }
}

std::optional<json> JobManager::status(const std::string& id) const {
  std::optional<engine::JobRecord> job = const_cast<engine::JobJournal&>(journal_).get(id);
  if (!job) return std::nullopt;
  json steps = json::array();
  for (const auto& s : job->steps) {
    json step{{"operation", s.operation}, {"kind", s.kind}, {"node", s.node}, {"state", s.state},
              {"run_ms", s.run_ms}, {"wait_ms", s.wait_ms}, {"transfer_ms", s.transfer_ms},
              {"update_ms", s.update_ms},
              {"sent", s.sent.empty() ? json() : json(s.sent)}, {"correction_bytes", s.correction_bytes},
              {"output_bytes", s.output_bytes}};
    step["value"] = s.value ? json(*s.value) : json();
    if (!s.error.empty()) step["error"] = s.error;
    steps.push_back(step);
  }
  return json{{"id", job->id}, {"state", engine::to_string(job->state)},
              {"error", job->error.empty() ? json() : json(job->error)}, {"created", job->created},
              {"transfer", job->transfer}, {"input_url", job->input_url.empty() ? json() : json(job->input_url)},
              {"broadcast_ms", job->broadcast_ms}, {"broadcast_bytes", job->broadcast_bytes},
              {"elapsed_ms", job->elapsed_ms},
              {"output_sha256", job->output_sha256.empty() ? json() : json(job->output_sha256)},
              {"steps", steps}};
}

bool JobManager::cancel(const std::string& id) {
  std::lock_guard lock(mutex_);
  auto it = cancel_.find(id);
  if (it == cancel_.end()) return false;
  *it->second = true;
  auto queued = std::find(queue_.begin(), queue_.end(), id);
  if (queued != queue_.end()) {
    queue_.erase(queued);
    journal_.set_state(id, engine::JobState::Cancelled, "cancelled before it started");
  }
  return true;
}

}  // namespace meshflow::web
