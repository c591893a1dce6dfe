#include "engine/job_journal.h"

#include <sqlite3.h>

#include <chrono>
#include <ctime>

#include "mesh/errors.h"

namespace meshflow::engine {
namespace {

// A prepared statement that finalizes itself; bind helpers keep call sites short.
class Statement {
 public:
  Statement(sqlite3* db, const char* sql) : db_(db) {
    if (sqlite3_prepare_v2(db, sql, -1, &stmt_, nullptr) != SQLITE_OK)
      throw IoError(std::string("job journal: ") + sqlite3_errmsg(db));
  }
  ~Statement() { sqlite3_finalize(stmt_); }
  Statement& text(int i, const std::string& v) {
    sqlite3_bind_text(stmt_, i, v.c_str(), -1, SQLITE_TRANSIENT);
    return *this;
  }
  Statement& integer(int i, std::int64_t v) {
    sqlite3_bind_int64(stmt_, i, v);
    return *this;
  }
  Statement& real(int i, std::optional<double> v) {
    if (v) sqlite3_bind_double(stmt_, i, *v);
    else sqlite3_bind_null(stmt_, i);
    return *this;
  }
  bool step() {
    int rc = sqlite3_step(stmt_);
    if (rc == SQLITE_ROW) return true;
    if (rc == SQLITE_DONE) return false;
    throw IoError(std::string("job journal: ") + sqlite3_errmsg(db_));
  }
  std::string column_text(int i) const {
    auto* p = sqlite3_column_text(stmt_, i);
    return p ? reinterpret_cast<const char*>(p) : "";
  }
  std::int64_t column_int(int i) const { return sqlite3_column_int64(stmt_, i); }
  std::optional<double> column_real(int i) const {
    if (sqlite3_column_type(stmt_, i) == SQLITE_NULL) return std::nullopt;
    return sqlite3_column_double(stmt_, i);
  }

 private:
  sqlite3* db_;
  sqlite3_stmt* stmt_ = nullptr;
};

std::string now_iso8601() {
  std::time_t t = std::time(nullptr);
  std::tm tm{};
  gmtime_r(&t, &tm);
  char buffer[32];
  std::strftime(buffer, sizeof buffer, "%Y-%m-%dT%H:%M:%SZ", &tm);
  return buffer;
}

const char* kSchema = R"sql(
PRAGMA journal_mode=WAL;
PRAGMA synchronous=NORMAL;
CREATE TABLE IF NOT EXISTS jobs (
  id TEXT PRIMARY KEY, state TEXT NOT NULL, workflow_xml TEXT NOT NULL, workflow_id TEXT,
  input_path TEXT, input_sha256 TEXT, output_path TEXT, output_sha256 TEXT, error TEXT,
  created TEXT NOT NULL, input_url TEXT, transfer TEXT, broadcast_ms INTEGER,
  broadcast_bytes INTEGER, elapsed_ms INTEGER);
CREATE TABLE IF NOT EXISTS steps (
  job_id TEXT NOT NULL, seq INTEGER NOT NULL, operation TEXT, kind TEXT, node TEXT, state TEXT,
  run_ms INTEGER, transfer_ms INTEGER, update_ms INTEGER, sent TEXT, correction_bytes INTEGER,
  output_bytes INTEGER, value REAL, output_sha256 TEXT, output_url TEXT, correction_url TEXT,
  error TEXT, wait_ms INTEGER, output_vertices INTEGER, PRIMARY KEY (job_id, seq));
)sql";

// Columns added after the first release: added to an older journal when it is opened.
const char* kAddedColumns[][2] = {
    {"jobs", "input_url TEXT"},         {"jobs", "transfer TEXT"},
    {"jobs", "broadcast_ms INTEGER"},   {"jobs", "broadcast_bytes INTEGER"},
    {"jobs", "elapsed_ms INTEGER"},     {"steps", "wait_ms INTEGER"},
    {"steps", "output_vertices INTEGER"},
};

bool has_column(sqlite3* db, const std::string& table, const std::string& column) {
  sqlite3_stmt* stmt = nullptr;
  std::string sql = "PRAGMA table_info(" + table + ")";
  sqlite3_prepare_v2(db, sql.c_str(), -1, &stmt, nullptr);
  bool found = false;
  while (sqlite3_step(stmt) == SQLITE_ROW)
    if (reinterpret_cast<const char*>(sqlite3_column_text(stmt, 1)) == column) found = true;
  sqlite3_finalize(stmt);
  return found;
}

}  // namespace

const char* to_string(JobState state) {
  switch (state) {
    case JobState::Queued: return "queued";
    case JobState::Running: return "running";
    case JobState::Done: return "done";
    case JobState::Failed: return "failed";
    case JobState::Cancelled: return "cancelled";
  }
  return "failed";
}

JobState job_state_from_string(const std::string& text) {
  if (text == "queued") return JobState::Queued;
  if (text == "running") return JobState::Running;
  if (text == "done") return JobState::Done;
  if (text == "cancelled") return JobState::Cancelled;
  return JobState::Failed;
}

JobJournal::JobJournal(const std::filesystem::path& file) {
  if (sqlite3_open(file.string().c_str(), &db_) != SQLITE_OK)
    throw IoError("cannot open the job journal " + file.string());
  sqlite3_busy_timeout(db_, 5000);
  char* error = nullptr;
  if (sqlite3_exec(db_, kSchema, nullptr, nullptr, &error) != SQLITE_OK) {
    std::string message = error ? error : "?";
    sqlite3_free(error);
    throw IoError("job journal " + file.string() + ": " + message);
  }
  for (const auto& [table, definition] : kAddedColumns) {
    std::string column = std::string(definition).substr(0, std::string(definition).find(' '));
    if (has_column(db_, table, column)) continue;
    std::string sql = std::string("ALTER TABLE ") + table + " ADD COLUMN " + definition;
    if (sqlite3_exec(db_, sql.c_str(), nullptr, nullptr, nullptr) != SQLITE_OK)
      throw IoError("job journal " + file.string() + ": " + sqlite3_errmsg(db_));
  }
}

JobJournal::~JobJournal() { sqlite3_close(db_); }

void JobJournal::create(const JobRecord& job) {
  std::lock_guard lock(mutex_);
  Statement(db_, "INSERT INTO jobs (id, state, workflow_xml, workflow_id, input_path, input_sha256,"
                 " created, input_url, transfer) VALUES (?,?,?,?,?,?,?,?,?)")
      .text(1, job.id)
      .text(2, to_string(job.state))
      .text(3, job.workflow_xml)
      .text(4, job.workflow_id)
      .text(5, job.input_path)
      .text(6, job.input_sha256)
      .text(7, job.created.empty() ? now_iso8601() : job.created)
      .text(8, job.input_url)
      .text(9, job.transfer)
      .step();
}

void JobJournal::set_state(const std::string& id, JobState state, const std::string& error) {
  std::lock_guard lock(mutex_);
  Statement(db_, "UPDATE jobs SET state = ?, error = ? WHERE id = ?")
      .text(1, to_string(state))
      .text(2, error)
      .text(3, id)
      .step();
}

void JobJournal::set_input(const std::string& id, const std::string& path,
                           const std::string& sha256) {
  std::lock_guard lock(mutex_);
  Statement(db_, "UPDATE jobs SET input_path = ?, input_sha256 = ? WHERE id = ?")
      .text(1, path)
      .text(2, sha256)
      .text(3, id)
      .step();
}

void JobJournal::set_output(const std::string& id, const std::string& path,
                            const std::string& sha256) {
  std::lock_guard lock(mutex_);
  Statement(db_, "UPDATE jobs SET output_path = ?, output_sha256 = ? WHERE id = ?")
      .text(1, path)
      .text(2, sha256)
      .text(3, id)
      .step();
}

void JobJournal::set_timings(const std::string& id, std::int64_t broadcast_ms, std::uint64_t broadcast_bytes,
                             std::int64_t elapsed_ms) {
  std::lock_guard lock(mutex_);
  Statement(db_, "UPDATE jobs SET broadcast_ms = ?, broadcast_bytes = ?, elapsed_ms = ? WHERE id = ?")
      .integer(1, broadcast_ms)
      .integer(2, static_cast<std::int64_t>(broadcast_bytes))
      .integer(3, elapsed_ms)
      .text(4, id)
      .step();
}

void JobJournal::put_step(const std::string& id, const StepRecord& s) {
  std::lock_guard lock(mutex_);
  Statement(db_, "INSERT OR REPLACE INTO steps (job_id, seq, operation, kind, node, state, run_ms,"
                 " transfer_ms, update_ms, sent, correction_bytes, output_bytes, value, output_sha256,"
                 " output_url, correction_url, error, wait_ms, output_vertices)"
                 " VALUES (?,?,?,?,?,?,?,?,?,?,?,?,?,?,?,?,?,?,?)")
      .text(1, id)
      .integer(2, s.seq)
      .text(3, s.operation)
      .text(4, s.kind)
      .text(5, s.node)
      .text(6, s.state)
      .integer(7, s.run_ms)
      .integer(8, s.transfer_ms)
      .integer(9, s.update_ms)
      .text(10, s.sent)
      .integer(11, static_cast<std::int64_t>(s.correction_bytes))
      .integer(12, static_cast<std::int64_t>(s.output_bytes))
      .real(13, s.value)
      .text(14, s.output_sha256)
      .text(15, s.output_url)
      .text(16, s.correction_url)
      .text(17, s.error)
      .integer(18, s.wait_ms)
      .integer(19, static_cast<std::int64_t>(s.output_vertices))
      .step();
}

std::optional<JobRecord> JobJournal::get(const std::string& id) const {
  std::lock_guard lock(mutex_);
  Statement job(db_, "SELECT id, state, workflow_xml, workflow_id, input_path, input_sha256,"
                     " output_path, output_sha256, error, created, input_url, transfer, broadcast_ms,"
                     " broadcast_bytes, elapsed_ms FROM jobs WHERE id = ?");
  job.text(1, id);
  if (!job.step()) return std::nullopt;
  JobRecord r;
  r.id = job.column_text(0);
  r.state = job_state_from_string(job.column_text(1));
  r.workflow_xml = job.column_text(2);
  r.workflow_id = job.column_text(3);
  r.input_path = job.column_text(4);
  r.input_sha256 = job.column_text(5);
  r.output_path = job.column_text(6);
  r.output_sha256 = job.column_text(7);
  r.error = job.column_text(8);
  r.created = job.column_text(9);
  r.input_url = job.column_text(10);
  r.transfer = job.column_text(11).empty() ? "smaller" : job.column_text(11);
  r.broadcast_ms = job.column_int(12);
  r.broadcast_bytes = static_cast<std::uint64_t>(job.column_int(13));
  r.elapsed_ms = job.column_int(14);
  Statement steps(db_, "SELECT seq, operation, kind, node, state, run_ms, transfer_ms, update_ms,"
                       " sent, correction_bytes, output_bytes, value, output_sha256, output_url,"
                       " correction_url, error, wait_ms, output_vertices FROM steps WHERE job_id = ?"
                       " ORDER BY seq");
  steps.text(1, id);
  while (steps.step()) {
    StepRecord s;
    s.seq = static_cast<int>(steps.column_int(0));
    s.operation = steps.column_text(1);
    s.kind = steps.column_text(2);
    s.node = steps.column_text(3);
    s.state = steps.column_text(4);
    s.run_ms = steps.column_int(5);
    s.transfer_ms = steps.column_int(6);
    s.update_ms = steps.column_int(7);
    s.sent = steps.column_text(8);
    s.correction_bytes = static_cast<std::uint64_t>(steps.column_int(9));
    s.output_bytes = static_cast<std::uint64_t>(steps.column_int(10));
    s.value = steps.column_real(11);
    s.output_sha256 = steps.column_text(12);
    s.output_url = steps.column_text(13);
    s.correction_url = steps.column_text(14);
    s.error = steps.column_text(15);
    s.wait_ms = steps.column_int(16);
    s.output_vertices = static_cast<std::uint64_t>(steps.column_int(17));
    r.steps.push_back(std::move(s));
  }
  return r;
}

std::vector<std::string> JobJournal::unfinished() const {
  std::lock_guard lock(mutex_);
  Statement q(db_, "SELECT id FROM jobs WHERE state IN ('queued','running') ORDER BY created");
  std::vector<std::string> ids;
  while (q.step()) ids.push_back(q.column_text(0));
  return ids;
}

std::vector<JobRecord> JobJournal::recent(std::size_t limit) const {
  std::lock_guard lock(mutex_);
  Statement q(db_, "SELECT id, state, workflow_id, error, created FROM jobs"
                   " ORDER BY created DESC LIMIT ?");
  q.integer(1, static_cast<std::int64_t>(limit));
  std::vector<JobRecord> jobs;
  while (q.step()) {
    JobRecord r;
    r.id = q.column_text(0);
    r.state = job_state_from_string(q.column_text(1));
    r.workflow_id = q.column_text(2);
    r.error = q.column_text(3);
    r.created = q.column_text(4);
    jobs.push_back(std::move(r));
  }
  return jobs;
}

}  // namespace meshflow::engine
