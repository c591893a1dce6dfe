#include "protocol/http_server.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <nlohmann/json.hpp>

#include "mesh/errors.h"

namespace meshflow::protocol {

namespace {

nlohmann::json where_of(const SourceLocation& where) {
  nlohmann::json out = nlohmann::json::object();
  if (!where.file.empty()) out["file"] = where.file;
  if (where.line) out["line"] = *where.line;
  if (where.column) out["column"] = *where.column;
  if (where.byte_offset) out["byte"] = *where.byte_offset;
  return out;
}

std::string body(const std::string& message, nlohmann::json where = nlohmann::json::object()) {
  return nlohmann::json{{"error", message}, {"where", std::move(where)}}.dump();
}

}  // namespace

ErrorReply error_reply(std::exception_ptr error) {
  try {
    std::rethrow_exception(error);
  } catch (const ParseError& e) {
    return {400, body(e.what(), where_of(e.where()))};
  } catch (const InvalidInput& e) {
    return {400, body(e.what())};
  } catch (const LimitExceeded& e) {
    return {413, body(e.what(), {{"limit", e.limit()}, {"actual", e.actual()}})};
  } catch (const NotFound& e) {
    return {404, body(e.what())};
  } catch (const Unauthorized& e) {
    return {401, body(e.what())};
  } catch (const Forbidden& e) {
    return {403, body(e.what())};
  } catch (const Unavailable& e) {
    return {503, body(e.what())};
  } catch (const IoError& e) {
    return {502, body(e.what())};
  } catch (const std::exception& e) {
    return {500, body(std::string("internal error: ") + e.what())};
  } catch (...) {
    return {500, body("internal error")};
  }
}

void reply_error(httplib::Response& res, int status, const std::string& message) {
  res.status = status;
  res.set_content(body(message), "application/json");
}

void install_error_handling(httplib::Server& server) {
  server.set_exception_handler(
      [](const httplib::Request&, httplib::Response& res, std::exception_ptr error) {
        ErrorReply reply = error_reply(error);
        res.status = reply.status;
        res.set_content(reply.body, "application/json");
      });
  // Failures found by httplib itself (no route, bad request line, payload too large) get the
  // same body; handlers that already wrote a body keep it.
  server.set_error_handler([](const httplib::Request& req, httplib::Response& res) {
    if (!res.body.empty()) return;
    std::string message = res.status == 404   ? "no such resource: " + req.path
                          : res.status == 413 ? "request body too large"
                          : res.status == 405 ? "method not allowed on " + req.path
                                              : "request failed";
    res.set_content(body(message), "application/json");
  });
}

void serve_file(const httplib::Request& req, httplib::Response& res, const std::string& path,
                const std::string& content_type) {
  int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) throw NotFound("no such file: " + path.substr(path.find_last_of('/') + 1));
  struct stat st{};
  if (::fstat(fd, &st) != 0) {
    ::close(fd);
    throw IoError("cannot stat " + path);
  }
  auto size = static_cast<std::uint64_t>(st.st_size);
  res.set_header("Accept-Ranges", "bytes");
  if (req.ranges.size() > 1) {
    ::close(fd);
    reply_error(res, 416, "only single ranges are supported");
    return;
  }
  if (req.ranges.size() == 1) {
    auto [first, last] = req.ranges[0];
    // httplib gives -1 for an open end or a suffix range.
    bool valid = size > 0 && ((first >= 0 && static_cast<std::uint64_t>(first) < size &&
                               (last < 0 || last >= first)) ||
                              (first < 0 && last > 0));
    if (!valid) {
      ::close(fd);
      res.set_header("Content-Range", "bytes */" + std::to_string(size));
      reply_error(res, 416, "range not satisfiable for a file of " + std::to_string(size) +
                                " bytes");
      return;
    }
  }
  // httplib slices the provider for a single valid range and sets Content-Range itself.
  res.set_content_provider(
      size, content_type,
      [fd](std::size_t offset, std::size_t length, httplib::DataSink& sink) {
        std::vector<char> buffer(std::min<std::size_t>(length, 1 << 20));
        std::size_t done = 0;
        while (done < length) {
          ssize_t n = ::pread(fd, buffer.data(), std::min(buffer.size(), length - done),
                              static_cast<off_t>(offset + done));
          if (n <= 0) return false;
          if (!sink.write(buffer.data(), static_cast<std::size_t>(n))) return false;
          done += static_cast<std::size_t>(n);
        }
        return true;
      },
      [fd](bool) { ::close(fd); });
}

}  // namespace meshflow::protocol
