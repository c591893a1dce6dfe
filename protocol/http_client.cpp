#include "protocol/http_client.h"

#include <curl/curl.h>
#include <zstd.h>

#include <cstdio>
#include <filesystem>
#include <memory>
#include <mutex>
#include <vector>

#include "mesh/canonical_ply.h"

namespace meshflow::protocol {
namespace {

void init_curl_once() {
  static std::once_flag once;
  std::call_once(once, [] { curl_global_init(CURL_GLOBAL_DEFAULT); });
}

struct CurlHandle {
  CURL* curl = curl_easy_init();
  curl_slist* headers = nullptr;
  ~CurlHandle() {
    curl_slist_free_all(headers);
    curl_easy_cleanup(curl);
  }
};

void common_options(CurlHandle& h, const std::string& url, const HttpOptions& options) {
  curl_easy_setopt(h.curl, CURLOPT_URL, url.c_str());
  curl_easy_setopt(h.curl, CURLOPT_NOSIGNAL, 1L);
  curl_easy_setopt(h.curl, CURLOPT_TIMEOUT_MS, static_cast<long>(options.timeout.count()));
  curl_easy_setopt(h.curl, CURLOPT_CONNECTTIMEOUT_MS,
                   static_cast<long>(options.connect_timeout.count()));
  curl_easy_setopt(h.curl, CURLOPT_BUFFERSIZE, 512L * 1024L);
  curl_easy_setopt(h.curl, CURLOPT_PROTOCOLS_STR, "http,https");
  if (!options.bearer_token.empty()) {
    std::string auth = "Authorization: Bearer " + options.bearer_token;
    h.headers = curl_slist_append(h.headers, auth.c_str());
  }
}

HttpResult finish(CurlHandle& h, CURLcode code) {
  HttpResult result;
  if (code != CURLE_OK) {
    result.error = curl_easy_strerror(code);
    return result;
  }
  long status = 0;
  curl_easy_getinfo(h.curl, CURLINFO_RESPONSE_CODE, &status);
  result.status = static_cast<int>(status);
  return result;
}

size_t append_to_string(char* data, size_t size, size_t count, void* user) {
  static_cast<std::string*>(user)->append(data, size * count);
  return size * count;
}

// Writes the body to a file while hashing it (decompressing zstd first when asked).
struct DownloadSink {
  std::FILE* file = nullptr;
  mesh::Sha256 hasher;
  ZSTD_DStream* zstd = nullptr;
  std::vector<char> out_buffer;
  std::uint64_t bytes = 0;
  bool failed = false;
  std::string error_body;  // kept for non-2xx answers
};

size_t write_download(char* data, size_t size, size_t count, void* user) {
  auto* sink = static_cast<DownloadSink*>(user);
  size_t n = size * count;
  sink->bytes += n;
  if (std::fwrite(data, 1, n, sink->file) != n) return 0;
  if (sink->error_body.size() < 4096) sink->error_body.append(data, std::min<size_t>(n, 4096));
  if (!sink->zstd) {
    sink->hasher.update(data, n);
    return n;
  }
  ZSTD_inBuffer in{data, n, 0};
  while (in.pos < in.size) {
    ZSTD_outBuffer out{sink->out_buffer.data(), sink->out_buffer.size(), 0};
    size_t rc = ZSTD_decompressStream(sink->zstd, &out, &in);
    if (ZSTD_isError(rc)) {
      sink->failed = true;
      return 0;
    }
    sink->hasher.update(sink->out_buffer.data(), out.pos);
  }
  return n;
}

}  // namespace

std::string HttpResult::describe() const {
  if (status == 0) return error.empty() ? "no response" : error;
  std::string text = "HTTP " + std::to_string(status);
  if (!body.empty()) text += ": " + body.substr(0, 300);
  return text;
}

HttpResult http_request(const std::string& method, const std::string& url,
                        const std::string& json_body, const HttpOptions& options) {
  init_curl_once();
  CurlHandle h;
  if (!h.curl) return {0, {}, "cannot create a libcurl handle"};
  common_options(h, url, options);
  std::string response;
  curl_easy_setopt(h.curl, CURLOPT_CUSTOMREQUEST, method.c_str());
  if (!json_body.empty() || method == "POST") {
    h.headers = curl_slist_append(h.headers, "Content-Type: application/json");
    curl_easy_setopt(h.curl, CURLOPT_POSTFIELDS, json_body.c_str());
    curl_easy_setopt(h.curl, CURLOPT_POSTFIELDSIZE, static_cast<long>(json_body.size()));
  }
  curl_easy_setopt(h.curl, CURLOPT_HTTPHEADER, h.headers);
  curl_easy_setopt(h.curl, CURLOPT_WRITEFUNCTION, append_to_string);
  curl_easy_setopt(h.curl, CURLOPT_WRITEDATA, &response);
  HttpResult result = finish(h, curl_easy_perform(h.curl));
  result.body = std::move(response);
  return result;
}

DownloadResult http_download(const std::string& url, const std::string& path,
                             const std::optional<std::string>& expected_sha256,
                             bool decompress_zstd, const HttpOptions& options) {
  init_curl_once();
  DownloadResult result;
  std::string tmp = path + ".tmp";
  DownloadSink sink;
  sink.file = std::fopen(tmp.c_str(), "wb");
  if (!sink.file) {
    result.error = "cannot create " + tmp;
    return result;
  }
  std::unique_ptr<ZSTD_DStream, decltype(&ZSTD_freeDStream)> zstd(
      decompress_zstd ? ZSTD_createDStream() : nullptr, ZSTD_freeDStream);
  if (decompress_zstd) {
    sink.zstd = zstd.get();
    sink.out_buffer.resize(ZSTD_DStreamOutSize());
  }
  CurlHandle h;
  common_options(h, url, options);
  curl_easy_setopt(h.curl, CURLOPT_HTTPHEADER, h.headers);
  curl_easy_setopt(h.curl, CURLOPT_WRITEFUNCTION, write_download);
  curl_easy_setopt(h.curl, CURLOPT_WRITEDATA, &sink);
  HttpResult http = finish(h, curl_easy_perform(h.curl));
  bool closed = std::fclose(sink.file) == 0;
  static_cast<HttpResult&>(result) = http;
  result.bytes = sink.bytes;
  std::error_code ignored;
  if (!result.ok()) {
    if (result.status != 0) result.body = sink.error_body;
    std::filesystem::remove(tmp, ignored);
    return result;
  }
  if (sink.failed || !closed) {
    std::filesystem::remove(tmp, ignored);
    return {{0, {}, sink.failed ? "corrupt zstd stream from " + url : "cannot write " + tmp}};
  }
  result.sha256 = sink.hasher.hex_digest();
  if (expected_sha256 && *expected_sha256 != result.sha256) {
    std::filesystem::remove(tmp, ignored);
    DownloadResult mismatch;
    mismatch.error = "SHA-256 mismatch for " + url + ": expected " + *expected_sha256 +
                     ", got " + result.sha256;
    return mismatch;
  }
  std::filesystem::rename(tmp, path);
  return result;
}

std::string url_origin(const std::string& url) {
  auto scheme_end = url.find("://");
  if (scheme_end == std::string::npos) return {};
  auto host_end = url.find('/', scheme_end + 3);
  return url.substr(0, host_end);
}

}  // namespace meshflow::protocol
