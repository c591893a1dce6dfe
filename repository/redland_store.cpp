#include "repository/redland_store.h"

#include <redland.h>
#include <rdf_storage_module.h>
#include <sqlite3.h>

#include <condition_variable>
#include <deque>
#include <functional>
#include <future>
#include <mutex>
#include <thread>
#include <limits>
#include <map>

#include "mesh/errors.h"

namespace meshflow::repository {
namespace {

// RAII for the librdf handles (each freed by its own function).
template <typename T, void (*Free)(T*)>
struct Handle {
  T* p = nullptr;
  explicit Handle(T* q = nullptr) : p(q) {}
  ~Handle() { if (p) Free(p); }
  Handle(const Handle&) = delete;
  Handle& operator=(const Handle&) = delete;
  T* get() const { return p; }
  explicit operator bool() const { return p != nullptr; }
};
using Node = Handle<librdf_node, librdf_free_node>;
using Query = Handle<librdf_query, librdf_free_query>;
using Results = Handle<librdf_query_results, librdf_free_query_results>;
using Stream = Handle<librdf_stream, librdf_free_stream>;
using Statement = Handle<librdf_statement, librdf_free_statement>;
using Serializer = Handle<librdf_serializer, librdf_free_serializer>;
using Parser = Handle<librdf_parser, librdf_free_parser>;
using Uri = Handle<librdf_uri, librdf_free_uri>;

const char* text(const unsigned char* s) { return reinterpret_cast<const char*>(s); }
const unsigned char* bytes(const std::string& s) {
  return reinterpret_cast<const unsigned char*>(s.c_str());
}

Term to_term(librdf_node* node) {
  Term t;
  if (!node) return t;
  if (librdf_node_is_resource(node)) {
    t.kind = Term::Kind::Uri;
    t.value = text(librdf_uri_as_string(librdf_node_get_uri(node)));
  } else if (librdf_node_is_literal(node)) {
    t.kind = Term::Kind::Literal;
    t.value = text(librdf_node_get_literal_value(node));
    if (const char* lang = librdf_node_get_literal_value_language(node)) t.language = lang;
    if (librdf_uri* dt = librdf_node_get_literal_value_datatype_uri(node))
      t.datatype = text(librdf_uri_as_string(dt));
  } else if (librdf_node_is_blank(node)) {
    t.kind = Term::Kind::Blank;
    t.value = text(librdf_node_get_blank_identifier(node));
  }
  return t;
}

// The deadline of the query running on this (worker) thread; triple streams end once it has
// passed, so that rasqal's joins and sorts run out of input and return.
using Clock = std::chrono::steady_clock;
thread_local Clock::time_point t_deadline = Clock::time_point::max();
thread_local bool t_overran = false;

bool overdue() {
  if (t_deadline == Clock::time_point::max()) return false;
  if (t_overran) return true;
  if (Clock::now() <= t_deadline) return false;
  t_overran = true;
  return true;
}

struct QueryDeadline {
  explicit QueryDeadline(Clock::time_point d) { t_deadline = d; t_overran = false; }
  ~QueryDeadline() { t_deadline = Clock::time_point::max(); }
  bool overran() const { return t_overran; }
};

}  // namespace
}  // namespace meshflow::repository

// Exported by librdf but not declared in its public headers.
extern "C" librdf_storage_factory* librdf_get_storage_factory(librdf_world* world,
                                                              const char* name);

namespace meshflow::repository {
namespace {

constexpr const char* kBoundedSqlite = "meshflow-bounded-sqlite";
librdf_storage_factory g_sqlite;  // the sqlite module's functions (same in every world)

int stream_end(void* c) { return overdue() || librdf_stream_end(static_cast<librdf_stream*>(c)); }
int stream_next(void* c) { return overdue() || librdf_stream_next(static_cast<librdf_stream*>(c)); }
void* stream_get(void* c, int flags) {
  auto* inner = static_cast<librdf_stream*>(c);
  if (flags == LIBRDF_STREAM_GET_METHOD_GET_CONTEXT) return librdf_stream_get_context2(inner);
  return librdf_stream_get_object(inner);
}
void stream_free(void* c) { librdf_free_stream(static_cast<librdf_stream*>(c)); }

librdf_stream* bounded(librdf_storage* storage, librdf_stream* inner) {
  if (!inner) return nullptr;
  librdf_stream* s = librdf_new_stream(librdf_storage_get_world(storage), inner, stream_end,
                                       stream_next, stream_get, stream_free);
  if (!s) librdf_free_stream(inner);
  return s;
}
librdf_stream* find_statements(librdf_storage* st, librdf_statement* pattern) {
  return bounded(st, g_sqlite.find_statements(st, pattern));
}
librdf_stream* find_in_context(librdf_storage* st, librdf_statement* pattern, librdf_node* ctx) {
  return bounded(st, g_sqlite.find_statements_in_context(st, pattern, ctx));
}
librdf_stream* find_with_options(librdf_storage* st, librdf_statement* pattern,
                                 librdf_node* ctx, librdf_hash* options) {
  return bounded(st, g_sqlite.find_statements_with_options(st, pattern, ctx, options));
}
int contains_statement(librdf_storage* st, librdf_statement* s) {
  return overdue() ? 0 : g_sqlite.contains_statement(st, s);
}

void bounded_factory(librdf_storage_factory* f) {
  char* name = f->name;
  char* label = f->label;
  *f = g_sqlite;
  f->name = name;
  f->label = label;
  f->find_statements = find_statements;
  if (g_sqlite.find_statements_in_context) f->find_statements_in_context = find_in_context;
  if (g_sqlite.find_statements_with_options) f->find_statements_with_options = find_with_options;
  if (g_sqlite.contains_statement) f->contains_statement = contains_statement;
}

// Registers the sqlite storage with bounded streams in `world`. \throws IoError.
void register_bounded_sqlite(librdf_world* world) {
  librdf_storage_factory* sqlite = librdf_get_storage_factory(world, "sqlite");
  if (!sqlite || !sqlite->find_statements)
    throw IoError("Redland has no sqlite storage (install librdf-storage-sqlite)");
  g_sqlite = *sqlite;
  if (librdf_storage_register_factory(world, kBoundedSqlite, "sqlite with query deadlines",
                                      bounded_factory) != 0)
    throw IoError("cannot register the bounded sqlite storage with Redland");
}

}  // namespace

struct RedlandStore::Impl {
  librdf_world* world = nullptr;
  librdf_storage* storage = nullptr;
  librdf_model* model = nullptr;
  sqlite3* reader = nullptr;         // the storage's file, read directly by subjects()
  sqlite3_stmt* subjects = nullptr;
  // subjects()'s answers until the next write: exact, as this process alone writes the store.
  std::map<std::pair<std::string, std::string>, std::vector<std::string>> subjects_memo;
  bool created = false;
  std::string last_log;  // the last message Redland logged (worker thread only)

  std::mutex mutex;
  std::condition_variable wake;
  std::deque<std::function<void()>> queue;
  bool stopping = false;
  std::thread worker;

  static int log_handler(void* user, librdf_log_message* message) {
    auto* self = static_cast<Impl*>(user);
    const char* m = librdf_log_message_message(message);
    if (m) {
      self->last_log = m;
      if (raptor_locator* loc = librdf_log_message_locator(message)) {
        int line = raptor_locator_line(loc);
        if (line > 0) self->last_log = "line " + std::to_string(line) + ": " + self->last_log;
      }
    }
    return 1;  // handled: nothing on stderr
  }

  void open(const std::filesystem::path& dir) {
    std::error_code ec;
    std::filesystem::create_directories(dir, ec);
    if (ec) throw IoError("cannot create the store folder " + dir.string() + ": " + ec.message());
    auto db = (dir / "store.db").string();
    created = !std::filesystem::exists(db);
    world = librdf_new_world();
    librdf_world_open(world);
    librdf_world_set_logger(world, this, &Impl::log_handler);
    std::string options = created ? "new='yes',synchronous='normal'" : "synchronous='normal'";
    register_bounded_sqlite(world);
    storage = librdf_new_storage(world, kBoundedSqlite, db.c_str(), options.c_str());
    if (!storage) throw IoError("cannot open the RDF store " + db + ": " + last_log);
    model = librdf_new_model(world, storage, nullptr);
    if (!model) throw IoError("cannot open the RDF model on " + db + ": " + last_log);
    // GROUND.md §1: without this index inserts slow down fivefold by 10k workflows.
    sqlite3* sql = nullptr;
    if (sqlite3_open(db.c_str(), &sql) == SQLITE_OK) {
      sqlite3_exec(sql, "CREATE INDEX IF NOT EXISTS litidx ON literals(text)", nullptr, nullptr,
                   nullptr);
    }
    sqlite3_close(sql);
    // subjects(): one pattern (?s p o) straight from the storage's tables, without building
    // librdf nodes and rasqal rows for thousands of matches; memory-mapped, as every call
    // scans the triples table (GROUND.md §1: no index on it).
    if (sqlite3_open_v2(db.c_str(), &reader, SQLITE_OPEN_READONLY, nullptr) != SQLITE_OK ||
        sqlite3_exec(reader, "PRAGMA mmap_size=1073741824; PRAGMA cache_size=-65536", nullptr,
                     nullptr, nullptr) != SQLITE_OK ||
        sqlite3_prepare_v2(reader,
                           "SELECT s.uri FROM triples t JOIN uris s ON s.id = t.subjectUri"
                           " WHERE t.predicateUri = (SELECT id FROM uris WHERE uri = ?1)"
                           " AND t.objectUri = (SELECT id FROM uris WHERE uri = ?2)",
                           -1, &subjects, nullptr) != SQLITE_OK)
      throw IoError("cannot read the RDF store " + db + ": " + sqlite3_errmsg(reader));
  }

  void close() {
    sqlite3_finalize(subjects);
    sqlite3_close(reader);
    subjects = nullptr; reader = nullptr;
    if (model) librdf_free_model(model);
    if (storage) librdf_free_storage(storage);
    if (world) librdf_free_world(world);
    model = nullptr; storage = nullptr; world = nullptr;
  }

  void loop() {
    for (;;) {
      std::function<void()> job;
      {
        std::unique_lock lock(mutex);
        wake.wait(lock, [&] { return stopping || !queue.empty(); });
        if (queue.empty()) return;
        job = std::move(queue.front());
        queue.pop_front();
      }
      job();
    }
  }

  // Runs `fn` on the worker thread and returns its future.
  template <typename F>
  auto submit(F fn) -> std::future<decltype(fn())> {
    auto task = std::make_shared<std::packaged_task<decltype(fn())()>>(std::move(fn));
    auto future = task->get_future();
    {
      std::lock_guard lock(mutex);
      queue.emplace_back([task] { (*task)(); });
    }
    wake.notify_one();
    return future;
  }
  template <typename F>
  auto run(F fn) { return submit(std::move(fn)).get(); }

  librdf_node* node(const std::string& uri) {
    return librdf_new_node_from_uri_string(world, bytes(uri));
  }

  void in_transaction(const std::function<void()>& body) {
    subjects_memo.clear();
    bool tx = librdf_model_transaction_start(model) == 0;
    try {
      body();
    } catch (...) {
      if (tx) librdf_model_transaction_rollback(model);
      throw;
    }
    if (tx && librdf_model_transaction_commit(model) != 0)
      throw IoError("the RDF store could not commit: " + last_log);
  }

  QueryResult query(const std::string& sparql, const QueryLimits& limits,
                    const std::string& graph_format,
                    std::chrono::steady_clock::time_point deadline) {
    last_log.clear();
    QueryDeadline bound(deadline);
    auto timeout = [&] {
      return QueryTimeout("the query ran past its time bound of " +
                          std::to_string(limits.timeout.count()) + " ms");
    };
    Query q(librdf_new_query(world, "sparql", nullptr, bytes(sparql), nullptr));
    if (!q)
      throw ParseError({"query", std::nullopt, std::nullopt, std::nullopt},
                       "SPARQL the Redland backend cannot parse (" +
                           (last_log.empty() ? std::string("syntax error") : last_log) +
                           "; rasqal 0.9.33 has no property paths, EXISTS or NOT EXISTS)");
    Results res(librdf_model_query_execute(model, q.get()));
    if (bound.overran()) throw timeout();
    if (!res)
      throw ParseError({"query", std::nullopt, std::nullopt, std::nullopt},
                       "the Redland backend could not run this query (" +
                           (last_log.empty() ? std::string("no reason given") : last_log) +
                           "; rasqal 0.9.33 fails on MINUS and DESCRIBE)");
    QueryResult out;
    if (librdf_query_results_is_boolean(res.get())) {
      out.kind = QueryResult::Kind::Boolean;
      out.boolean = librdf_query_results_get_boolean(res.get()) > 0;
      if (bound.overran()) throw timeout();
      return out;
    }
    if (librdf_query_results_is_graph(res.get())) {
      out.kind = QueryResult::Kind::Graph;
      Stream stream(librdf_query_results_as_stream(res.get()));
      Serializer ser(librdf_new_serializer(world, graph_format.c_str(), nullptr, nullptr));
      if (!stream || !ser) throw IoError("cannot serialize the graph as " + graph_format);
      size_t length = 0;
      unsigned char* s = librdf_serializer_serialize_stream_to_counted_string(
          ser.get(), nullptr, stream.get(), &length);
      if (s) {
        out.graph.assign(text(s), length);
        librdf_free_memory(s);
      }
      if (bound.overran()) throw timeout();
      return out;
    }
    int count = librdf_query_results_get_bindings_count(res.get());
    for (int i = 0; i < count; ++i)
      out.variables.emplace_back(librdf_query_results_get_binding_name(res.get(), i));
    while (!librdf_query_results_finished(res.get())) {
      if (out.rows.size() >= limits.max_rows)
        throw LimitExceeded("query result rows (add a LIMIT or narrow the query)",
                            limits.max_rows, out.rows.size() + 1);
      if (overdue()) throw timeout();
      std::vector<Term> row;
      row.reserve(count);
      for (int i = 0; i < count; ++i) {
        Node value(librdf_query_results_get_binding_value(res.get(), i));
        row.push_back(to_term(value.get()));
      }
      out.rows.push_back(std::move(row));
      librdf_query_results_next(res.get());
    }
    if (bound.overran()) throw timeout();
    return out;
  }
};

RedlandStore::RedlandStore(const std::filesystem::path& dir) : impl_(std::make_unique<Impl>()) {
  impl_->worker = std::thread([this] { impl_->loop(); });
  try {
    impl_->run([&] { impl_->open(dir); return 0; });
  } catch (...) {
    impl_->run([&] { impl_->close(); return 0; });
    { std::lock_guard lock(impl_->mutex); impl_->stopping = true; }
    impl_->wake.notify_one();
    impl_->worker.join();
    throw;
  }
}

RedlandStore::~RedlandStore() {
  impl_->run([&] { impl_->close(); return 0; });
  { std::lock_guard lock(impl_->mutex); impl_->stopping = true; }
  impl_->wake.notify_one();
  impl_->worker.join();
}

bool RedlandStore::created_now() const { return impl_->created; }

QueryResult RedlandStore::query(const std::string& sparql, const QueryLimits& limits,
                            const std::string& graph_format) {
  auto deadline = std::chrono::steady_clock::now() + limits.timeout;
  auto future = impl_->submit([impl = impl_.get(), sparql, limits, graph_format, deadline] {
    return impl->query(sparql, limits, graph_format, deadline);
  });
  // The streams end at the deadline, so rasqal returns soon after it; the caller is answered
  // at the bound in any case.
  if (future.wait_until(deadline + std::chrono::milliseconds(200)) != std::future_status::ready)
    throw QueryTimeout("the query ran past its time bound of " +
                       std::to_string(limits.timeout.count()) + " ms");
  return future.get();
}

std::vector<std::string> RedlandStore::subjects(const std::string& predicate,
                                                const std::string& object) {
  return impl_->run([&] {
    auto key = std::make_pair(predicate, object);
    if (auto hit = impl_->subjects_memo.find(key); hit != impl_->subjects_memo.end())
      return hit->second;
    std::vector<std::string> out;
    sqlite3_stmt* q = impl_->subjects;
    sqlite3_reset(q);
    sqlite3_bind_text(q, 1, predicate.c_str(), static_cast<int>(predicate.size()), SQLITE_STATIC);
    sqlite3_bind_text(q, 2, object.c_str(), static_cast<int>(object.size()), SQLITE_STATIC);
    int rc;
    while ((rc = sqlite3_step(q)) == SQLITE_ROW)
      if (auto* uri = sqlite3_column_text(q, 0)) out.emplace_back(text(uri));
    sqlite3_reset(q);
    if (rc != SQLITE_DONE)
      throw IoError(std::string("cannot read the RDF store: ") + sqlite3_errmsg(impl_->reader));
    if (impl_->subjects_memo.size() >= 256) impl_->subjects_memo.clear();
    impl_->subjects_memo.emplace(key, out);
    return out;
  });
}

void RedlandStore::load_rdfxml(const std::string& document, const std::string& base_uri) {
  impl_->run([&] {
    impl_->last_log.clear();
    Parser parser(librdf_new_parser(impl_->world, "rdfxml", nullptr, nullptr));
    Uri base(librdf_new_uri(impl_->world, bytes(base_uri)));
    impl_->in_transaction([&] {
      if (librdf_parser_parse_string_into_model(parser.get(), bytes(document), base.get(),
                                                impl_->model) != 0)
        throw ParseError({base_uri, std::nullopt, std::nullopt, std::nullopt},
                         "not valid RDF/XML: " + impl_->last_log);
    });
    return 0;
  });
}

void RedlandStore::add(const std::vector<Triple>& triples) {
  impl_->run([&] {
    impl_->in_transaction([&] {
      for (const auto& t : triples) {
        librdf_node* object;
        if (t.literal) {
          Uri dt(t.datatype.empty() ? nullptr
                                    : librdf_new_uri(impl_->world, bytes(t.datatype)));
          object = dt ? librdf_new_node_from_typed_literal(impl_->world, bytes(t.object),
                                                           nullptr, dt.get())
                      : librdf_new_node_from_literal(impl_->world, bytes(t.object), nullptr, 0);
        } else {
          object = impl_->node(t.object);
        }
        Statement s(librdf_new_statement_from_nodes(impl_->world, impl_->node(t.subject),
                                                    impl_->node(t.predicate), object));
        if (!s || librdf_model_add_statement(impl_->model, s.get()) != 0)
          throw IoError("cannot add a triple about " + t.subject + ": " + impl_->last_log);
      }
    });
    return 0;
  });
}

void RedlandStore::remove_subject(const std::string& subject) {
  impl_->run([&] {
    impl_->in_transaction([&] {
      Statement pattern(librdf_new_statement_from_nodes(impl_->world, impl_->node(subject),
                                                        nullptr, nullptr));
      std::vector<librdf_statement*> found;
      {
        Stream stream(librdf_model_find_statements(impl_->model, pattern.get()));
        while (stream && !librdf_stream_end(stream.get())) {
          found.push_back(librdf_new_statement_from_statement(
              librdf_stream_get_object(stream.get())));
          librdf_stream_next(stream.get());
        }
      }
      for (auto* s : found) {
        librdf_model_remove_statement(impl_->model, s);
        librdf_free_statement(s);
      }
    });
    return 0;
  });
}

std::uint64_t RedlandStore::size() {
  return impl_->run([&] {
    int n = librdf_model_size(impl_->model);
    return static_cast<std::uint64_t>(n < 0 ? 0 : n);
  });
}

}  // namespace meshflow::repository
