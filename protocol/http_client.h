#pragma once
// The transfer client (libcurl): JSON calls between hub and nodes, and streamed downloads of
// meshes and corrections checked against their SHA-256. Failures that are expected at run
// time (connection refused, timeout, HTTP errors) come back as values, so the caller decides
// whether to retry elsewhere (STYLE §4).

#include <chrono>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

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
  // Connect only to public addresses (never loopback, private, link-local, CGNAT, multicast or
  // reserved ranges), checked on every connection libcurl opens, redirects included, so DNS
  // tricks cannot reach inside: for URLs that users give the hub (DESIGN §3).
  bool public_only = false;
  bool follow_redirects = false;  // up to 5, http and https only
  std::uint64_t max_bytes = 0;    // downloads: give up past this many bytes (0: no limit)
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

// A multipart/form-data POST (what a browser form sends): text fields, and files streamed from
// disk. The answer's body is returned as with http_request.
struct FormPart {
  std::string name;
  std::string value;      // the text of a field
  std::string file_path;  // or: a file streamed from disk (value is then ignored)
};
HttpResult http_post_form(const std::string& url, const std::vector<FormPart>& parts,
                          const HttpOptions& options = {});

// Scheme, host and port of a URL ("http://127.0.0.1:8080"), for allow-lists.
std::string url_origin(const std::string& url);

// Whether a numeric IPv4 or IPv6 address is public (IPv4-mapped and NAT64 IPv6 addresses are
// judged by the IPv4 address inside). Anything that does not parse is not public.
bool is_public_address(const std::string& ip);

// Resolves the host of an http(s) URL; "" when every address is public, else why not
// ("127.0.0.1 is a loopback or private address", "cannot resolve ..."). The check that counts
// is the one at connection time (HttpOptions::public_only); this one gives an early answer.
std::string why_not_public(const std::string& url);

}  // namespace meshflow::protocol
