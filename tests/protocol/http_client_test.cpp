#include "protocol/http_client.h"

#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

namespace meshflow::protocol {
namespace {

TEST(PublicAddress, RefusesLoopbackPrivateLinkLocalAndReservedIPv4) {
  for (const char* ip : {"127.0.0.1", "127.255.0.9", "10.0.0.1", "172.16.0.1", "172.31.255.255", "192.168.1.1",
                         "169.254.169.254", "100.64.0.1", "0.0.0.0", "224.0.0.1", "255.255.255.255", "198.18.0.1",
                         "192.0.2.1"})
    EXPECT_FALSE(is_public_address(ip)) << ip;
  for (const char* ip : {"8.8.8.8", "1.1.1.1", "172.32.0.1", "192.169.0.1", "100.128.0.1", "151.101.1.69"})
    EXPECT_TRUE(is_public_address(ip)) << ip;
}

TEST(PublicAddress, JudgesIPv6AndTheIPv4InsideMappedAddresses) {
  for (const char* ip : {"::1", "::", "fe80::1", "fc00::1", "fd12:3456::1", "ff02::1", "::ffff:127.0.0.1",
                         "::ffff:10.1.2.3", "64:ff9b::a9fe:a9fe", "2001:db8::1", "::127.0.0.1"})
    EXPECT_FALSE(is_public_address(ip)) << ip;
  for (const char* ip : {"2606:4700:4700::1111", "2a00:1450:4001:80b::200e", "::ffff:8.8.8.8"})
    EXPECT_TRUE(is_public_address(ip)) << ip;
  EXPECT_FALSE(is_public_address("not an address"));
  EXPECT_FALSE(is_public_address(""));
}

TEST(WhyNotPublic, NamesTheAddressOrTheScheme) {
  EXPECT_NE(why_not_public("http://127.0.0.1:8080/x.ply").find("127.0.0.1, a loopback or private address"),
            std::string::npos);
  EXPECT_NE(why_not_public("http://localhost/x.ply").find("loopback or private"), std::string::npos);
  EXPECT_NE(why_not_public("http://[::1]:9/x").find("loopback or private"), std::string::npos);
  EXPECT_NE(why_not_public("file:///etc/passwd").find("only http and https"), std::string::npos);
  EXPECT_NE(why_not_public("gopher://8.8.8.8/").find("only http and https"), std::string::npos);
  EXPECT_EQ(why_not_public("http://8.8.8.8/mesh.ply"), "");  // numeric: no DNS needed
}

TEST(PublicOnlyFetch, NeverConnectsToLoopback) {
  // A listener on loopback that accepts connections (in its backlog) and never answers.
  int listener = socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in address{};
  address.sin_family = AF_INET;
  address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  ASSERT_EQ(bind(listener, reinterpret_cast<sockaddr*>(&address), sizeof address), 0);
  ASSERT_EQ(listen(listener, 4), 0);
  socklen_t length = sizeof address;
  getsockname(listener, reinterpret_cast<sockaddr*>(&address), &length);
  std::string url = "http://127.0.0.1:" + std::to_string(ntohs(address.sin_port)) + "/mesh.ply";
  HttpOptions options;
  options.timeout = std::chrono::milliseconds(500);
  // Without the rule the request gets through and waits for an answer...
  DownloadResult open = http_download(url, "/tmp/meshflow-public-only-test.bin", std::nullopt, false, options);
  EXPECT_FALSE(open.ok());
  EXPECT_EQ(open.error.find("only public addresses"), std::string::npos) << open.error;
  // ...with it, no connection is ever made.
  options.public_only = true;
  DownloadResult refused = http_download(url, "/tmp/meshflow-public-only-test.bin", std::nullopt, false, options);
  EXPECT_FALSE(refused.ok());
  EXPECT_NE(refused.error.find("only public addresses"), std::string::npos) << refused.error;
  EXPECT_NE(refused.error, open.error);
  close(listener);
}

}  // namespace
}  // namespace meshflow::protocol
