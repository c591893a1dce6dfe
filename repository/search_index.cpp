#include "repository/search_index.h"

#include <sqlite3.h>

#include <mutex>
#include <nlohmann/json.hpp>

#include "mesh/errors.h"

namespace meshflow::repository {
namespace {

struct Stmt {
  sqlite3_stmt* s = nullptr;
  Stmt(sqlite3* db, const char* sql) {
    if (sqlite3_prepare_v2(db, sql, -1, &s, nullptr) != SQLITE_OK)
      throw IoError(std::string("search index: ") + sqlite3_errmsg(db));
  }
  ~Stmt() { sqlite3_finalize(s); }
  Stmt& bind(int i, const std::string& v) {
    sqlite3_bind_text(s, i, v.c_str(), static_cast<int>(v.size()), SQLITE_TRANSIENT);
    return *this;
  }
  bool row() { return sqlite3_step(s) == SQLITE_ROW; }
  void done(sqlite3* db) {
    if (sqlite3_step(s) != SQLITE_DONE)
      throw IoError(std::string("search index: ") + sqlite3_errmsg(db));
  }
  std::string text(int i) {
    auto p = sqlite3_column_text(s, i);
    return p ? reinterpret_cast<const char*>(p) : "";
  }
};

}  // namespace

struct SearchIndex::Impl {
  sqlite3* db = nullptr;
  std::mutex mutex;
  std::optional<std::vector<std::string>> newest;  // newest_first's answer until the next write
};

SearchIndex::SearchIndex(const std::filesystem::path& file) : impl_(std::make_unique<Impl>()) {
  if (sqlite3_open(file.string().c_str(), &impl_->db) != SQLITE_OK)
    throw IoError("cannot open " + file.string());
  const char* schema =
      "PRAGMA journal_mode=WAL; PRAGMA synchronous=NORMAL; PRAGMA mmap_size=1073741824;"
      "CREATE TABLE IF NOT EXISTS workflows(id TEXT PRIMARY KEY, name TEXT, description TEXT,"
      " creator TEXT, created TEXT, type TEXT, domains TEXT);"
      "CREATE INDEX IF NOT EXISTS workflows_created ON workflows(created);"
      "CREATE VIRTUAL TABLE IF NOT EXISTS workflows_fts USING fts5(id UNINDEXED, name, description);";
  if (sqlite3_exec(impl_->db, schema, nullptr, nullptr, nullptr) != SQLITE_OK)
    throw IoError(std::string("search index: ") + sqlite3_errmsg(impl_->db));
}

SearchIndex::~SearchIndex() { sqlite3_close(impl_->db); }

void SearchIndex::put(const WorkflowSummary& w) {
  std::lock_guard lock(impl_->mutex);
  impl_->newest.reset();
  sqlite3_exec(impl_->db, "BEGIN", nullptr, nullptr, nullptr);
  try {
    Stmt(impl_->db, "DELETE FROM workflows_fts WHERE id = ?").bind(1, w.id).done(impl_->db);
    Stmt(impl_->db, "INSERT OR REPLACE INTO workflows VALUES(?, ?, ?, ?, ?, ?, ?)")
        .bind(1, w.id).bind(2, w.name).bind(3, w.description).bind(4, w.creator)
        .bind(5, w.created).bind(6, w.type).bind(7, nlohmann::json(w.domains).dump())
        .done(impl_->db);
    Stmt(impl_->db, "INSERT INTO workflows_fts(id, name, description) VALUES(?, ?, ?)")
        .bind(1, w.id).bind(2, w.name).bind(3, w.description).done(impl_->db);
  } catch (...) {
    sqlite3_exec(impl_->db, "ROLLBACK", nullptr, nullptr, nullptr);
    throw;
  }
  sqlite3_exec(impl_->db, "COMMIT", nullptr, nullptr, nullptr);
}

void SearchIndex::remove(const std::string& id) {
  std::lock_guard lock(impl_->mutex);
  impl_->newest.reset();
  Stmt(impl_->db, "DELETE FROM workflows_fts WHERE id = ?").bind(1, id).done(impl_->db);
  Stmt(impl_->db, "DELETE FROM workflows WHERE id = ?").bind(1, id).done(impl_->db);
}

bool SearchIndex::empty() {
  std::lock_guard lock(impl_->mutex);
  Stmt q(impl_->db, "SELECT 1 FROM workflows LIMIT 1");
  return !q.row();
}

void SearchIndex::clear() {
  std::lock_guard lock(impl_->mutex);
  impl_->newest.reset();
  if (sqlite3_exec(impl_->db, "DELETE FROM workflows_fts; DELETE FROM workflows;", nullptr, nullptr,
                   nullptr) != SQLITE_OK)
    throw IoError(std::string("search index: ") + sqlite3_errmsg(impl_->db));
}

namespace {
// Every word as a quoted prefix term: "w1"* AND "w2"*.
std::string fts_expression(const std::vector<std::string>& words) {
  std::string expr;
  for (const auto& w : words) {
    std::string quoted;
    for (char c : w) quoted += c == '"' ? std::string("\"\"") : std::string(1, c);
    expr += (expr.empty() ? "" : " AND ") + ("\"" + quoted + "\"*");
  }
  return expr;
}
}  // namespace

std::vector<std::string> SearchIndex::match_page(const std::vector<std::string>& words,
                                                 std::uint64_t offset, std::uint64_t limit,
                                                 std::uint64_t& total) {
  std::string expr = fts_expression(words);
  std::lock_guard lock(impl_->mutex);
  Stmt count(impl_->db, "SELECT count(*) FROM workflows_fts WHERE workflows_fts MATCH ?");
  count.bind(1, expr);
  total = count.row() ? static_cast<std::uint64_t>(sqlite3_column_int64(count.s, 0)) : 0;
  Stmt q(impl_->db,
         "SELECT id FROM workflows_fts WHERE workflows_fts MATCH ?"
         " ORDER BY bm25(workflows_fts, 0.0, 3.0, 1.0), rowid DESC LIMIT ? OFFSET ?");
  q.bind(1, expr);
  sqlite3_bind_int64(q.s, 2, static_cast<sqlite3_int64>(limit));
  sqlite3_bind_int64(q.s, 3, static_cast<sqlite3_int64>(offset));
  std::vector<std::string> ids;
  while (q.row()) ids.push_back(q.text(0));
  return ids;
}

std::vector<std::string> SearchIndex::match(const std::vector<std::string>& words) {
  std::string expr = fts_expression(words);
  std::lock_guard lock(impl_->mutex);
  // Ties in rank: the later row first (a workflow's row is rewritten when it is stored).
  Stmt q(impl_->db,
         "SELECT id FROM workflows_fts WHERE workflows_fts MATCH ?"
         " ORDER BY bm25(workflows_fts, 0.0, 3.0, 1.0), rowid DESC");
  q.bind(1, expr);
  std::vector<std::string> ids;
  while (q.row()) ids.push_back(q.text(0));
  return ids;
}

std::vector<std::string> SearchIndex::newest_first() {
  std::lock_guard lock(impl_->mutex);
  if (!impl_->newest) {
    Stmt q(impl_->db, "SELECT id FROM workflows ORDER BY created DESC, id");
    std::vector<std::string> ids;
    while (q.row()) ids.push_back(q.text(0));
    impl_->newest = std::move(ids);
  }
  return *impl_->newest;
}

std::optional<WorkflowSummary> SearchIndex::summary(const std::string& id) {
  std::lock_guard lock(impl_->mutex);
  Stmt q(impl_->db, "SELECT name, description, creator, created, type, domains FROM workflows WHERE id = ?");
  q.bind(1, id);
  if (!q.row()) return std::nullopt;
  WorkflowSummary w{id, q.text(0), q.text(1), q.text(2), q.text(3), {}, q.text(4)};
  w.domains = nlohmann::json::parse(q.text(5)).get<std::vector<std::string>>();
  return w;
}

}  // namespace meshflow::repository
