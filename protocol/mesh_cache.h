#pragma once
// The node's download and update modules (thesis §4.3.1, DESIGN §4, §6): a cache of meshes
// on disk, keyed by URL in an SQLite table (URL -> local file, SHA-256, state), that never
// fetches the same URL twice. Downloads and updates are one-way: they start in the
// background and callers wait for the mesh when they need it. Meshes are stored as the
// canonical binary PLY, zstd-compressed, named by the SHA-256 of the uncompressed bytes.

#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <list>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <set>
#include <string>
#include <thread>
#include <vector>

#include "mesh/mesh.h"

struct sqlite3;

namespace meshflow::protocol {

enum class CacheState { Pending, Ready, Failed };
const char* to_string(CacheState state);

struct CacheEntry {
  std::string url;
  CacheState state = CacheState::Pending;
  std::string sha256;       // of the canonical PLY (known when ready, or expected up front)
  std::string error;        // when failed
  std::int64_t ms = 0;      // time the download or update took
  std::string how;          // "download", "update", "update-fallback", "local"
  std::uint64_t bytes = 0;  // received on the wire (the correction, or the whole mesh)
  std::int64_t fetch_ms = 0;  // of `ms`, fetching those bytes
  std::int64_t apply_ms = 0;  // of `ms`, applying the correction (or loading the mesh)
};

struct MeshCacheOptions {
  std::filesystem::path dir;                 // holds cache.sqlite and meshes/
  std::size_t memory_meshes = 4;             // meshes kept loaded (LRU)
  std::chrono::milliseconds fetch_timeout{std::chrono::minutes(30)};
  // Origins (scheme://host:port) the cache may fetch from; empty = any. The node allows the
  // hub and the registered nodes only (DESIGN §10).
  std::set<std::string> allowed_origins;
};

class MeshCache {
 public:
  explicit MeshCache(MeshCacheOptions options);
  ~MeshCache();
  MeshCache(const MeshCache&) = delete;
  MeshCache& operator=(const MeshCache&) = delete;

  void allow_origin(const std::string& origin);

  // Starts fetching `url` unless the cache already has (or is fetching) it. The file at `url`
  // is a .ply.zst in canonical form; its hash is checked against `sha256` when given.
  // \throws InvalidInput when the URL's origin is not allowed.
  void download(const std::string& url, const std::optional<std::string>& sha256);

  // Starts an update: fetch the correction at `correction_url`, apply it to the cached mesh
  // `base_sha256`, and cache the outcome under `result_url`; when the result's hash is not
  // `result_sha256` (or anything fails) the whole result is downloaded from `result_url`.
  void update(const std::string& base_sha256, const std::string& correction_url,
              const std::string& result_url, const std::string& result_sha256);

  // The state of the entry whose URL or SHA-256 is `key`.
  std::optional<CacheEntry> find(const std::string& key) const;

  // Waits for a pending download or update of `key` (URL or SHA-256), then returns the mesh
  // (loading it from disk if needed) and how long it waited. If the cache has never heard of
  // a URL key, downloads it first. \throws IoError when the fetch failed or timed out,
  // InvalidInput for an unknown SHA-256 key.
  struct Loaded {
    std::shared_ptr<const mesh::Mesh> mesh;
    std::string sha256;
    std::int64_t wait_ms = 0;
  };
  Loaded wait_mesh(const std::string& key, std::chrono::milliseconds timeout);

  // Stores a mesh the node produced; returns its SHA-256. The compressed file is at
  // file_path(sha) afterwards.
  std::string store(std::shared_ptr<const mesh::Mesh> mesh);

  // Stores bytes under files/ (corrections); returns the path.
  std::filesystem::path store_file(const std::string& name, const std::string& bytes);

  std::filesystem::path mesh_path(const std::string& sha256) const;  // meshes/<sha>.ply.zst
  std::filesystem::path files_dir() const;

 private:
  struct Job;
  void worker_loop();
  void run_download(const std::string& url, const std::optional<std::string>& sha256);
  void run_update(const std::string& base, const std::string& correction_url,
                  const std::string& result_url, const std::string& result_sha256);
  void set_entry(const CacheEntry& entry);
  void remember(const std::string& sha256, std::shared_ptr<const mesh::Mesh> mesh);
  void store_as(std::shared_ptr<const mesh::Mesh> mesh, const std::string& sha256);
  void check_origin(const std::string& url) const;
  const CacheEntry* by_expected_sha(const std::string& sha256) const;  // \pre mutex_ held

  MeshCacheOptions options_;
  sqlite3* db_ = nullptr;
  mutable std::mutex mutex_;
  std::condition_variable changed_;
  std::map<std::string, CacheEntry> entries_;          // by URL
  std::map<std::string, std::string> url_of_sha_;      // ready entries by hash
  std::list<std::pair<std::string, std::shared_ptr<const mesh::Mesh>>> loaded_;  // LRU
  std::vector<std::thread> workers_;
  std::list<std::function<void()>> queue_;
  bool stopping_ = false;
};

}  // namespace meshflow::protocol
