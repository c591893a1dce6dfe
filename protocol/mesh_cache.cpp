#include "protocol/mesh_cache.h"

#include <sqlite3.h>

#include <fstream>
#include <sstream>

#include "mesh/canonical_ply.h"
#include "mesh/errors.h"
#include "mesh/mesh_io.h"
#include "protocol/correction.h"
#include "protocol/http_client.h"

namespace meshflow::protocol {
namespace {

constexpr int kWorkers = 4;

std::int64_t elapsed_ms(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration_cast<std::chrono::milliseconds>(std::chrono::steady_clock::now() -
                                                               start)
      .count();
}

bool is_sha256(const std::string& key) {
  return key.size() == 64 && key.find_first_not_of("0123456789abcdef") == std::string::npos;
}

void exec(sqlite3* db, const char* sql) {
  char* error = nullptr;
  if (sqlite3_exec(db, sql, nullptr, nullptr, &error) != SQLITE_OK) {
    std::string message = error ? error : "unknown error";
    sqlite3_free(error);
    throw IoError(std::string("cache database: ") + message);
  }
}

}  // namespace

const char* to_string(CacheState state) {
  switch (state) {
    case CacheState::Pending: return "pending";
    case CacheState::Ready: return "ready";
    case CacheState::Failed: return "failed";
  }
  return "failed";
}

MeshCache::MeshCache(MeshCacheOptions options) : options_(std::move(options)) {
  std::filesystem::create_directories(options_.dir / "meshes");
  std::filesystem::create_directories(options_.dir / "files");
  std::string db_path = (options_.dir / "cache.sqlite").string();
  if (sqlite3_open(db_path.c_str(), &db_) != SQLITE_OK)
    throw IoError("cannot open the cache database " + db_path);
  exec(db_, "PRAGMA journal_mode=WAL;"
            "CREATE TABLE IF NOT EXISTS cache (url TEXT PRIMARY KEY, sha256 TEXT NOT NULL,"
            " path TEXT NOT NULL, how TEXT NOT NULL, ms INTEGER NOT NULL);");
  // Ready entries survive a restart when their file is still there; pending ones never
  // reach the table, so an interrupted fetch is simply fetched again.
  sqlite3_stmt* stmt = nullptr;
  sqlite3_prepare_v2(db_, "SELECT url, sha256, path, how, ms FROM cache", -1, &stmt, nullptr);
  while (sqlite3_step(stmt) == SQLITE_ROW) {
    CacheEntry entry;
    entry.url = reinterpret_cast<const char*>(sqlite3_column_text(stmt, 0));
    entry.sha256 = reinterpret_cast<const char*>(sqlite3_column_text(stmt, 1));
    std::string path = reinterpret_cast<const char*>(sqlite3_column_text(stmt, 2));
    entry.how = reinterpret_cast<const char*>(sqlite3_column_text(stmt, 3));
    entry.ms = sqlite3_column_int64(stmt, 4);
    entry.state = CacheState::Ready;
    if (!std::filesystem::exists(path)) continue;
    url_of_sha_[entry.sha256] = entry.url;
    entries_[entry.url] = std::move(entry);
  }
  sqlite3_finalize(stmt);
  for (int i = 0; i < kWorkers; ++i) workers_.emplace_back([this] { worker_loop(); });
}

MeshCache::~MeshCache() {
  {
    std::lock_guard lock(mutex_);
    stopping_ = true;
  }
  changed_.notify_all();
  for (auto& worker : workers_) worker.join();
  sqlite3_close(db_);
}

void MeshCache::allow_origin(const std::string& origin) {
  std::lock_guard lock(mutex_);
  options_.allowed_origins.insert(origin);
}

void MeshCache::check_origin(const std::string& url) const {
  if (options_.allowed_origins.empty()) return;
  if (!options_.allowed_origins.count(url_origin(url)))
    throw InvalidInput("refusing to fetch from " + url_origin(url) +
                       ": not the hub or a registered node");
}

std::filesystem::path MeshCache::mesh_path(const std::string& sha256) const {
  return options_.dir / "meshes" / (sha256 + ".ply.zst");
}

std::filesystem::path MeshCache::files_dir() const { return options_.dir / "files"; }

void MeshCache::worker_loop() {
  for (;;) {
    std::function<void()> job;
    {
      std::unique_lock lock(mutex_);
      changed_.wait(lock, [&] { return stopping_ || !queue_.empty(); });
      if (stopping_) return;
      job = std::move(queue_.front());
      queue_.pop_front();
    }
    job();
  }
}

void MeshCache::download(const std::string& url, const std::optional<std::string>& sha256) {
  std::lock_guard lock(mutex_);
  check_origin(url);
  auto it = entries_.find(url);
  if (it != entries_.end() && it->second.state != CacheState::Failed) return;
  if (sha256 && url_of_sha_.count(*sha256)) {
    // Same content under another URL: no fetch, just a second name.
    CacheEntry alias = entries_.at(url_of_sha_.at(*sha256));
    alias.url = url;
    alias.how = "local";
    alias.ms = alias.fetch_ms = alias.apply_ms = 0;
    alias.bytes = 0;
    entries_[url] = alias;
    return;
  }
  entries_[url] = CacheEntry{url, CacheState::Pending, sha256.value_or(""), "", 0, "download"};
  queue_.push_back([this, url, sha256] { run_download(url, sha256); });
  changed_.notify_all();
}

void MeshCache::update(const std::string& base_sha256, const std::string& correction_url,
                       const std::string& result_url, const std::string& result_sha256) {
  std::lock_guard lock(mutex_);
  check_origin(correction_url);
  check_origin(result_url);
  auto it = entries_.find(result_url);
  if (it != entries_.end() && it->second.state != CacheState::Failed) return;
  if (url_of_sha_.count(result_sha256)) {
    CacheEntry alias = entries_.at(url_of_sha_.at(result_sha256));
    alias.url = result_url;
    alias.how = "local";
    alias.ms = alias.fetch_ms = alias.apply_ms = 0;
    alias.bytes = 0;
    entries_[result_url] = alias;
    return;
  }
  entries_[result_url] = CacheEntry{result_url, CacheState::Pending, result_sha256, "", 0, "update"};
  queue_.push_back([=, this] { run_update(base_sha256, correction_url, result_url, result_sha256); });
  changed_.notify_all();
}

void MeshCache::run_download(const std::string& url, const std::optional<std::string>& sha256) {
  auto start = std::chrono::steady_clock::now();
  CacheEntry entry{url, CacheState::Failed, sha256.value_or(""), "", 0, "download"};
  std::filesystem::path tmp = options_.dir / "meshes" / ("download-" + std::to_string(
      std::hash<std::string>{}(url)) + ".ply.zst");
  HttpOptions http;
  http.timeout = options_.fetch_timeout;
  DownloadResult result = http_download(url, tmp.string(), sha256, /*decompress_zstd=*/true, http);
  entry.fetch_ms = elapsed_ms(start);
  entry.bytes = result.bytes;
  if (result.ok()) {
    std::filesystem::path final_path = mesh_path(result.sha256);
    std::error_code ignored;
    std::filesystem::rename(tmp, final_path, ignored);
    // Loaded now, as an update leaves its result loaded: the next /run finds it in memory.
    auto loading = std::chrono::steady_clock::now();
    try {
      remember(result.sha256, std::make_shared<mesh::Mesh>(mesh::read_mesh(final_path.string())));
      entry.state = CacheState::Ready;
      entry.sha256 = result.sha256;
    } catch (const std::exception& e) {
      entry.error = "download of " + url + " is not a readable mesh: " + e.what();
      std::filesystem::remove(final_path, ignored);
    }
    entry.apply_ms = elapsed_ms(loading);
  } else {
    entry.error = "download of " + url + " failed: " + result.describe();
  }
  entry.ms = elapsed_ms(start);
  set_entry(entry);
}

void MeshCache::run_update(const std::string& base, const std::string& correction_url,
                           const std::string& result_url, const std::string& result_sha256) {
  auto start = std::chrono::steady_clock::now();
  CacheEntry entry{result_url, CacheState::Failed, result_sha256, "", 0, "update"};
  try {
    Loaded loaded = wait_mesh(base, options_.fetch_timeout);
    std::filesystem::path correction_path =
        files_dir() / ("fetched-" + std::to_string(std::hash<std::string>{}(correction_url)) +
                       ".mfc");
    HttpOptions http;
    http.timeout = options_.fetch_timeout;
    auto fetching = std::chrono::steady_clock::now();
    DownloadResult fetched = http_download(correction_url, correction_path.string(),
                                           std::nullopt, false, http);
    entry.fetch_ms = elapsed_ms(fetching);
    entry.bytes = fetched.bytes;
    if (!fetched.ok()) throw IoError("correction " + correction_url + ": " + fetched.describe());
    auto applying = std::chrono::steady_clock::now();
    std::ifstream in(correction_path, std::ios::binary);
    std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    std::span<const std::uint8_t> correction(reinterpret_cast<const std::uint8_t*>(bytes.data()), bytes.size());
    // Checked before anything is stored: a mismatching mesh is never kept. apply_correction
    // checks the base's hash and that the result is the one the correction promises.
    CorrectionHeader header = read_correction_header(correction);
    if (header.result_sha256 != result_sha256)
      throw IoError("the correction yields " + header.result_sha256 + ", not the producer's " + result_sha256);
    auto result = std::make_shared<mesh::Mesh>(apply_correction(*loaded.mesh, correction));
    const std::string& sha = result_sha256;
    store_as(result, sha);
    entry.apply_ms = elapsed_ms(applying);
    entry.state = CacheState::Ready;
    entry.sha256 = sha;
  } catch (const std::exception& e) {
    // The thesis's fallback: fetch the whole result instead.
    std::string why = e.what();
    std::filesystem::path tmp = options_.dir / "meshes" / ("fallback-" + result_sha256 + ".ply.zst");
    HttpOptions http;
    http.timeout = options_.fetch_timeout;
    auto fetching = std::chrono::steady_clock::now();
    DownloadResult whole = http_download(result_url, tmp.string(), result_sha256, true, http);
    entry.fetch_ms += elapsed_ms(fetching);
    entry.bytes += whole.bytes;
    if (whole.ok()) {
      std::error_code ignored;
      std::filesystem::rename(tmp, mesh_path(result_sha256), ignored);
      entry.state = CacheState::Ready;
      entry.how = "update-fallback";
      entry.error = why;  // why the correction was not used
    } else {
      entry.error = "update failed (" + why + ") and so did the whole download: " + whole.describe();
    }
  }
  entry.ms = elapsed_ms(start);
  set_entry(entry);
}

void MeshCache::set_entry(const CacheEntry& entry) {
  std::lock_guard lock(mutex_);
  entries_[entry.url] = entry;
  if (entry.state == CacheState::Ready) {
    url_of_sha_[entry.sha256] = entry.url;
    sqlite3_stmt* stmt = nullptr;
    sqlite3_prepare_v2(db_, "INSERT OR REPLACE INTO cache VALUES (?,?,?,?,?)", -1, &stmt, nullptr);
    std::string path = mesh_path(entry.sha256).string();
    sqlite3_bind_text(stmt, 1, entry.url.c_str(), -1, SQLITE_TRANSIENT);
    sqlite3_bind_text(stmt, 2, entry.sha256.c_str(), -1, SQLITE_TRANSIENT);
    sqlite3_bind_text(stmt, 3, path.c_str(), -1, SQLITE_TRANSIENT);
    sqlite3_bind_text(stmt, 4, entry.how.c_str(), -1, SQLITE_TRANSIENT);
    sqlite3_bind_int64(stmt, 5, entry.ms);
    sqlite3_step(stmt);
    sqlite3_finalize(stmt);
  }
  changed_.notify_all();
}

std::optional<CacheEntry> MeshCache::find(const std::string& key) const {
  std::lock_guard lock(mutex_);
  auto it = entries_.find(key);
  if (it != entries_.end()) return it->second;
  auto by_sha = url_of_sha_.find(key);
  if (by_sha != url_of_sha_.end()) return entries_.at(by_sha->second);
  if (const CacheEntry* entry = by_expected_sha(key)) return *entry;
  return std::nullopt;
}

// An entry not ready yet, known by the hash it should yield: a pending one before a failed one
// (a download that failed may have been asked again from elsewhere).
const CacheEntry* MeshCache::by_expected_sha(const std::string& sha256) const {
  const CacheEntry* failed = nullptr;
  for (const auto& [url, entry] : entries_) {
    if (entry.sha256 != sha256) continue;
    if (entry.state != CacheState::Failed) return &entry;
    failed = &entry;
  }
  return failed;
}

MeshCache::Loaded MeshCache::wait_mesh(const std::string& key, std::chrono::milliseconds timeout) {
  auto start = std::chrono::steady_clock::now();
  if (!find(key)) {
    if (is_sha256(key)) throw InvalidInput("no mesh with SHA-256 " + key + " on this node");
    download(key, std::nullopt);
  }
  std::string sha;
  {
    std::unique_lock lock(mutex_);
    auto current = [&]() -> const CacheEntry* {
      auto it = entries_.find(key);
      if (it != entries_.end()) return &it->second;
      auto by_sha = url_of_sha_.find(key);
      if (by_sha != url_of_sha_.end()) return &entries_.at(by_sha->second);
      return by_expected_sha(key);
    };
    bool settled = changed_.wait_for(lock, timeout, [&] {
      const CacheEntry* e = current();
      return !e || e->state != CacheState::Pending;
    });
    const CacheEntry* entry = current();
    if (!settled) throw IoError("timed out waiting for " + key);
    if (!entry) throw IoError("lost track of " + key);
    if (entry->state == CacheState::Failed) throw IoError(entry->error);
    sha = entry->sha256;
    for (auto it = loaded_.begin(); it != loaded_.end(); ++it) {
      if (it->first != sha) continue;
      loaded_.splice(loaded_.begin(), loaded_, it);
      return {it->second, sha, elapsed_ms(start)};
    }
  }
  auto mesh = std::make_shared<mesh::Mesh>(mesh::read_mesh(mesh_path(sha).string()));
  remember(sha, mesh);
  return {mesh, sha, elapsed_ms(start)};
}

void MeshCache::remember(const std::string& sha256, std::shared_ptr<const mesh::Mesh> mesh) {
  std::lock_guard lock(mutex_);
  for (auto it = loaded_.begin(); it != loaded_.end(); ++it)
    if (it->first == sha256) {
      loaded_.erase(it);
      break;
    }
  loaded_.emplace_front(sha256, std::move(mesh));
  while (loaded_.size() > options_.memory_meshes) loaded_.pop_back();
}

std::string MeshCache::store(std::shared_ptr<const mesh::Mesh> mesh) {
  std::string sha = mesh::mesh_sha256(*mesh);
  store_as(mesh, sha);
  return sha;
}

void MeshCache::store_as(std::shared_ptr<const mesh::Mesh> mesh, const std::string& sha) {
  std::filesystem::path path = mesh_path(sha);
  if (!std::filesystem::exists(path)) mesh::write_mesh(*mesh, path.string());
  remember(sha, mesh);
  std::string url = "local:" + sha;
  set_entry(CacheEntry{url, CacheState::Ready, sha, "", 0, "local"});
}

std::filesystem::path MeshCache::store_file(const std::string& name, const std::string& bytes) {
  std::filesystem::path path = files_dir() / name;
  std::filesystem::path tmp = path;
  tmp += ".tmp";
  {
    std::ofstream out(tmp, std::ios::binary);
    out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
    if (!out) throw IoError("cannot write " + tmp.string());
  }
  std::filesystem::rename(tmp, path);
  return path;
}

}  // namespace meshflow::protocol
