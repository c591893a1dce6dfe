#pragma once
// The transfer client (libcurl): JSON calls between hub and nodes, and streamed downloads of
// meshes and corrections checked against their SHA-256. Failures that are expected at run
// time (connection refused, timeout, HTTP errors) come back as values, so the caller decides
// whether to retry elsewhere (STYLE §4).

#include <chrono>
#include <cstdint>
#include <optional>
#include <string>

namespace meshflow::protocol {

struct HttpResult {
  int status = 0;        // HTTP status; 0 when no response arrived
  std::string body;      // response body (JSON calls) or empty (downloads)
  std::string error;     // transport error text when status == 0
  bool ok() const { return status >= 200 && status < 300; }
  std::string describe() const;  // "HTTP 404: {...}" or "connection refused ..."
};

struct HttpOptions {
  std::chrono::milliseconds timeout{std::chrono::minutes(10)};
  std::chrono::milliseconds connect_timeout{std::chrono::seconds(5)};
  std::string bearer_token;  // sent as "Authorization: Bearer ..." when not empty
};

// A request with an optional JSON body ("GET", "POST", "DELETE"...).
HttpResult http_request(const std::string& method, const std::string& url,
                        const std::string& json_body = {}, const HttpOptions& options = {});

// Streams `url` to `path` (written to path.tmp, renamed on success). When `expected_sha256`
// is given, the SHA-256 of the bytes (after zstd decompression when `decompress_zstd`) must
// match, else the file is removed and the result reports the mismatch (status 0).
struct DownloadResult : HttpResult {
  std::uint64_t bytes = 0;   // bytes received on the wire
  std::string sha256;        // of the (decompressed) content
};
DownloadResult http_download(const std::string& url, const std::string& path,
                             const std::optional<std::string>& expected_sha256 = std::nullopt,
                             bool decompress_zstd = false, const HttpOptions& options = {});

// Scheme, host and port of a URL ("http://127.0.0.1:8080"), for allow-lists.
std::string url_origin(const std::string& url);

}  // namespace meshflow::protocol
