#include "web/job_manager.h"

#include <openssl/rand.h>

#include <fstream>
#include <sstream>

#include "engine/executor.h"
#include "engine/http_node_client.h"
#include "engine/validate.h"
#include "engine/workflow_parser.h"
#include "mesh/canonical_ply.h"
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
      if (!r->output_url.empty()) live_.set_current(r->output_url, r->output_sha256);
      return report_of(*r);
    }
    return live_.run_atomic(operation, params);
  }
  engine::StepReport run_analysis(const std::string& operation) override {
    if (const engine::StepRecord* r = next(operation)) return report_of(*r);
    return live_.run_analysis(operation);
  }
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
    report.transfer_ms = r.transfer_ms;
    report.update_ms = r.update_ms;
    report.sent = r.sent;
    report.correction_bytes = r.correction_bytes;
    report.output_bytes = r.output_bytes;
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
  for (int i = 0; i < workers; ++i) workers_.emplace_back([this] { worker(); });
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
  engine::Workflow workflow = engine::parse_workflow(workflow_xml, "workflow.xml");
  engine::validate_workflow(workflow, "workflow.xml", services::operation_specs());
  std::string id = upload.parent_path().filename().string();
  mesh::Mesh input = mesh::read_mesh(upload.string());
  mesh::write_mesh(input, input_file(id).string());
  std::filesystem::remove(upload);
  engine::JobRecord job;
  job.id = id;
  job.workflow_xml = workflow_xml;
  job.input_path = input_file(id).string();
  job.input_sha256 = mesh::mesh_sha256(input);
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

void JobManager::run(const std::string& id) {
  std::optional<engine::JobRecord> job = journal_.get(id);
  if (!job) return;
  std::shared_ptr<std::atomic<bool>> cancelled;
  {
    std::lock_guard lock(mutex_);
    cancelled = cancel_[id];
  }
  journal_.set_state(id, engine::JobState::Running);
  try {
    engine::Workflow workflow = engine::parse_workflow(job->workflow_xml, "workflow.xml");
    engine::ValidatedWorkflow valid = engine::validate_workflow(workflow, "workflow.xml", services::operation_specs());
    // Nodes taking part: every registered node offering an operation the workflow uses.
    std::vector<std::string> used = engine::operations_used(workflow);
    engine::HttpNodeOptions options;
    options.token = token_;
    for (const auto& s : services_.list())
      for (const auto& op : used)
        if (s.offers(op)) {
          options.nodes.push_back(s.url);
          break;
        }
    options.pick = [this](const std::string& op, const std::vector<std::string>& exclude) {
      return services_.choose(op, exclude);
    };
    options.load = [this](const std::string& node, int delta) { services_.adjust_load(node, delta); };
    options.cancelled = [cancelled] { return cancelled->load(); };
    mesh::Mesh input = mesh::read_mesh(job->input_path);
    options.reference_diagonal = mesh::bounding_box(input).diagonal();
    std::string input_url = hub_url_ + "/api/jobs/" + id + "/input";
    engine::HttpNodeClient live(options, input_url, job->input_sha256);
    live.broadcast_input();
    std::vector<engine::StepRecord> done;
    for (const auto& s : job->steps)
      if (s.state == "done") done.push_back(s);
    ReplayingNodes nodes(done, live);
    int seq = 0;
    engine::ExecutorOptions exec;
    exec.cancelled = [cancelled] { return cancelled->load(); };
    exec.on_step = [&](const engine::StepReport& r) {
      engine::StepRecord s;
      s.seq = seq++;
      s.operation = r.operation;
      s.kind = r.is_analysis ? "analysis" : "atomic";
      s.node = r.node;
      s.state = "done";
      s.run_ms = r.run_ms;
      s.transfer_ms = r.transfer_ms;
      s.update_ms = r.update_ms;
      s.sent = r.sent;
      s.correction_bytes = r.correction_bytes;
      s.output_bytes = r.output_bytes;
      if (r.is_analysis) s.value = r.value;
      s.output_sha256 = live.current_sha256();
      s.output_url = live.current_url();
      journal_.put_step(id, s);
    };
    engine::execute(valid, nodes, exec);
    // The result travels once, to the hub, for the user.
    std::filesystem::path fetched = job_dir(id) / "output.ply.zst";
    protocol::HttpOptions http;
    http.timeout = std::chrono::minutes(30);
    protocol::DownloadResult got =
        protocol::http_download(live.current_url(), fetched.string(), live.current_sha256(), true, http);
    if (!got.ok()) throw IoError("fetching the result from " + live.current_url() + ": " + got.describe());
    mesh::Mesh output = mesh::read_mesh(fetched.string());
    mesh::write_mesh(output, output_file(id).string());
    std::filesystem::remove(fetched);
    journal_.set_output(id, output_file(id).string(), live.current_sha256());
    journal_.set_state(id, engine::JobState::Done);
  } catch (const std::exception& e) {
    journal_.set_state(id, cancelled->load() ? engine::JobState::Cancelled : engine::JobState::Failed, e.what());
  }
}

std::optional<json> JobManager::status(const std::string& id) const {
  std::optional<engine::JobRecord> job = const_cast<engine::JobJournal&>(journal_).get(id);
  if (!job) return std::nullopt;
  json steps = json::array();
  for (const auto& s : job->steps) {
    json step{{"operation", s.operation}, {"kind", s.kind}, {"node", s.node}, {"state", s.state},
              {"run_ms", s.run_ms}, {"transfer_ms", s.transfer_ms}, {"update_ms", s.update_ms},
              {"sent", s.sent.empty() ? json() : json(s.sent)}, {"correction_bytes", s.correction_bytes},
              {"output_bytes", s.output_bytes}};
    step["value"] = s.value ? json(*s.value) : json();
    steps.push_back(step);
  }
  return json{{"id", job->id}, {"state", engine::to_string(job->state)},
              {"error", job->error.empty() ? json() : json(job->error)}, {"created", job->created},
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
