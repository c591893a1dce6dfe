#include "protocol/http_client.h"

#include <arpa/inet.h>
#include <curl/curl.h>
#include <netdb.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <zstd.h>

#include <algorithm>
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

bool is_public_v4(std::uint32_t a) {  // host byte order
  auto in = [a](std::uint32_t net, int bits) { return (a >> (32 - bits)) == (net >> (32 - bits)); };
  return !(in(0x00000000, 8) ||    // "this" network
           in(0x0A000000, 8) ||    // 10/8
           in(0x64400000, 10) ||   // 100.64/10 carrier-grade NAT
           in(0x7F000000, 8) ||    // loopback
           in(0xA9FE0000, 16) ||   // link-local (cloud metadata lives here)
           in(0xAC100000, 12) ||   // 172.16/12
           in(0xC0000000, 24) ||   // 192.0.0/24 protocol assignments
           in(0xC0000200, 24) ||   // TEST-NET-1
           in(0xC0A80000, 16) ||   // 192.168/16
           in(0xC6120000, 15) ||   // 198.18/15 benchmarking
           in(0xC6336400, 24) ||   // TEST-NET-2
           in(0xCB007100, 24) ||   // TEST-NET-3
           in(0xE0000000, 4) ||    // multicast
           in(0xF0000000, 4));     // reserved and broadcast
}

bool is_public_v6(const unsigned char* b) {
  static const unsigned char mapped[12] = {0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0xff, 0xff};
  static const unsigned char nat64[12] = {0, 0x64, 0xff, 0x9b, 0, 0, 0, 0, 0, 0, 0, 0};
  auto v4 = [b] { return std::uint32_t(b[12]) << 24 | std::uint32_t(b[13]) << 16 | std::uint32_t(b[14]) << 8 | b[15]; };
  if (std::equal(mapped, mapped + 12, b) || std::equal(nat64, nat64 + 12, b)) return is_public_v4(v4());
  bool zero_prefix = std::all_of(b, b + 15, [](unsigned char c) { return c == 0; });
  if (zero_prefix && (b[15] == 0 || b[15] == 1)) return false;  // :: and ::1
  if (std::all_of(b, b + 12, [](unsigned char c) { return c == 0; })) return false;  // IPv4-compatible
  if ((b[0] & 0xfe) == 0xfc) return false;                   // fc00::/7 unique local
  if (b[0] == 0xfe && (b[1] & 0xc0) == 0x80) return false;   // fe80::/10 link-local
  if (b[0] == 0xfe && (b[1] & 0xc0) == 0xc0) return false;   // fec0::/10 site-local
  if (b[0] == 0xff) return false;                            // multicast
  if (b[0] == 0x20 && b[1] == 0x01 && b[2] == 0x0d && b[3] == 0xb8) return false;  // documentation
  return true;
}

bool is_public_sockaddr(const sockaddr* address) {
  if (address->sa_family == AF_INET)
    return is_public_v4(ntohl(reinterpret_cast<const sockaddr_in*>(address)->sin_addr.s_addr));
  if (address->sa_family == AF_INET6)
    return is_public_v6(reinterpret_cast<const sockaddr_in6*>(address)->sin6_addr.s6_addr);
  return false;
}

// libcurl asks this for every socket it opens (redirects and DNS answers included).
curl_socket_t open_public_socket(void*, curlsocktype purpose, curl_sockaddr* address) {
  if (purpose != CURLSOCKTYPE_IPCXN || !is_public_sockaddr(&address->addr)) return CURL_SOCKET_BAD;
  return socket(address->family, address->socktype, address->protocol);
}

void common_options(CurlHandle& h, const std::string& url, const HttpOptions& options) {
  curl_easy_setopt(h.curl, CURLOPT_URL, url.c_str());
  curl_easy_setopt(h.curl, CURLOPT_NOSIGNAL, 1L);
  curl_easy_setopt(h.curl, CURLOPT_TIMEOUT_MS, static_cast<long>(options.timeout.count()));
  curl_easy_setopt(h.curl, CURLOPT_CONNECTTIMEOUT_MS,
                   static_cast<long>(options.connect_timeout.count()));
  curl_easy_setopt(h.curl, CURLOPT_BUFFERSIZE, 512L * 1024L);
  curl_easy_setopt(h.curl, CURLOPT_PROTOCOLS_STR, "http,https");
  if (options.public_only) curl_easy_setopt(h.curl, CURLOPT_OPENSOCKETFUNCTION, open_public_socket);
  if (options.follow_redirects) {
    curl_easy_setopt(h.curl, CURLOPT_FOLLOWLOCATION, 1L);
    curl_easy_setopt(h.curl, CURLOPT_MAXREDIRS, 5L);
    curl_easy_setopt(h.curl, CURLOPT_REDIR_PROTOCOLS_STR, "http,https");
  }
  if (options.max_bytes > 0)
    curl_easy_setopt(h.curl, CURLOPT_MAXFILESIZE_LARGE, static_cast<curl_off_t>(options.max_bytes));
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
  std::uint64_t max_bytes = 0;  // 0: no limit
  bool too_big = false;
  bool failed = false;
  std::string error_body;  // kept for non-2xx answers
};

size_t write_download(char* data, size_t size, size_t count, void* user) {
  auto* sink = static_cast<DownloadSink*>(user);
  size_t n = size * count;
  sink->bytes += n;
  if (sink->max_bytes > 0 && sink->bytes > sink->max_bytes) {
    sink->too_big = true;
    return 0;
  }
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

HttpResult http_post_form(const std::string& url, const std::vector<FormPart>& parts,
                          const HttpOptions& options) {
  init_curl_once();
  CurlHandle h;
  if (!h.curl) return {0, {}, "cannot create a libcurl handle"};
  common_options(h, url, options);
  std::unique_ptr<curl_mime, decltype(&curl_mime_free)> mime(curl_mime_init(h.curl), curl_mime_free);
  for (const auto& part : parts) {
    curl_mimepart* field = curl_mime_addpart(mime.get());
    curl_mime_name(field, part.name.c_str());
    if (part.file_path.empty()) {
      curl_mime_data(field, part.value.data(), part.value.size());
    } else if (curl_mime_filedata(field, part.file_path.c_str()) != CURLE_OK) {
      return {0, {}, "cannot read " + part.file_path};
    }
  }
  std::string response;
  curl_easy_setopt(h.curl, CURLOPT_MIMEPOST, mime.get());
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
  sink.max_bytes = options.max_bytes;
  CurlHandle h;
  common_options(h, url, options);
  curl_easy_setopt(h.curl, CURLOPT_HTTPHEADER, h.headers);
  curl_easy_setopt(h.curl, CURLOPT_WRITEFUNCTION, write_download);
  curl_easy_setopt(h.curl, CURLOPT_WRITEDATA, &sink);
  HttpResult http = finish(h, curl_easy_perform(h.curl));
  bool closed = std::fclose(sink.file) == 0;
  if (sink.too_big || (http.status == 0 && http.error == curl_easy_strerror(CURLE_FILESIZE_EXCEEDED)))
    http = {0, {}, url + " is larger than the limit of " + std::to_string(options.max_bytes) + " bytes"};
  else if (http.status == 0 && options.public_only && http.error == curl_easy_strerror(CURLE_COULDNT_CONNECT))
    http.error += " (only public addresses are fetched: loopback and private ranges are refused)";
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

bool is_public_address(const std::string& ip) {
  in_addr v4{};
  if (inet_pton(AF_INET, ip.c_str(), &v4) == 1) return is_public_v4(ntohl(v4.s_addr));
  in6_addr v6{};
  if (inet_pton(AF_INET6, ip.c_str(), &v6) == 1) return is_public_v6(v6.s6_addr);
  return false;
}

std::string why_not_public(const std::string& url) {
  init_curl_once();
  CURLU* parsed = curl_url();
  std::unique_ptr<CURLU, decltype(&curl_url_cleanup)> guard(parsed, curl_url_cleanup);
  if (curl_url_set(parsed, CURLUPART_URL, url.c_str(), 0) != CURLUE_OK) return "not a URL: " + url;
  char* scheme = nullptr;
  char* host = nullptr;
  curl_url_get(parsed, CURLUPART_SCHEME, &scheme, 0);
  curl_url_get(parsed, CURLUPART_HOST, &host, 0);
  std::string scheme_text = scheme ? scheme : "", host_text = host ? host : "";
  curl_free(scheme);
  curl_free(host);
  if (scheme_text != "http" && scheme_text != "https") return "only http and https URLs are fetched, not " + url;
  if (host_text.size() > 2 && host_text.front() == '[') host_text = host_text.substr(1, host_text.size() - 2);
  addrinfo hints{};
  hints.ai_socktype = SOCK_STREAM;
  addrinfo* found = nullptr;
  if (getaddrinfo(host_text.c_str(), nullptr, &hints, &found) != 0 || !found)
    return "cannot resolve the host " + host_text;
  std::string why;
  for (addrinfo* a = found; a && why.empty(); a = a->ai_next) {
    if (is_public_sockaddr(a->ai_addr)) continue;
    char text[INET6_ADDRSTRLEN] = "?";
    const void* raw = a->ai_family == AF_INET
                          ? static_cast<const void*>(&reinterpret_cast<sockaddr_in*>(a->ai_addr)->sin_addr)
                          : static_cast<const void*>(&reinterpret_cast<sockaddr_in6*>(a->ai_addr)->sin6_addr);
    inet_ntop(a->ai_family, raw, text, sizeof text);
    why = host_text + " resolves to " + text + ", a loopback or private address";
  }
  freeaddrinfo(found);
  return why;
}

std::string url_origin(const std::string& url) {
  auto scheme_end = url.find("://");
  if (scheme_end == std::string::npos) return {};
  auto host_end = url.find('/', scheme_end + 3);
  return url.substr(0, host_end);
}

}  // namespace meshflow::protocol
