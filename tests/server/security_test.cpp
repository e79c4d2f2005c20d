// Tests for server/security.hpp: the Host and Origin policy, token comparison, ids, static path
// resolution and download names, as pure functions (the end-to-end corpus is in server_test.cpp).
#include "server/security.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

namespace {

namespace fs = std::filesystem;
using server::HostPolicy;

TEST(HostPolicy, LoopbackNamesWithTheRightPortAreAllowed) {
  const HostPolicy p("127.0.0.1", 8080, 8081);
  for (const char* host :
       {"127.0.0.1:8080", "localhost:8080", "LocalHost:8080", "localhost.:8080", "[::1]:8080"}) {
    EXPECT_TRUE(p.host_allowed(host, 8080)) << host;
  }
  EXPECT_TRUE(p.host_allowed("127.0.0.1:8081", p.ws_port()));
  for (const char* host : {"127.0.0.1:8081", "127.0.0.1", "127.0.0.1:", ":8080", "127.0.0.1:80x0",
                           "127.0.0.1:0008080", "evil.example:8080", "localhost.evil.example:8080",
                           "10.0.0.1:8080", "[::2]:8080", "[::1:8080", ""}) {
    EXPECT_FALSE(p.host_allowed(host, 8080)) << host;
  }
}

TEST(HostPolicy, AListenHostAddsItsNameAndAWildcardTheAddressesItListensOn) {
  const HostPolicy lan("192.168.1.5", 8080, 8081);
  EXPECT_TRUE(lan.host_allowed("192.168.1.5:8080", 8080));
  EXPECT_FALSE(lan.host_allowed("192.168.1.6:8080", 8080));
  EXPECT_EQ(lan.page_origin(), "http://192.168.1.5:8080");

  const HostPolicy any("0.0.0.0", 8080, 8081, {"10.1.2.3", "FE80::1"});
  EXPECT_TRUE(any.host_allowed("10.1.2.3:8080", 8080));
  EXPECT_TRUE(any.host_allowed("[fe80::1]:8080", 8080));
  EXPECT_TRUE(any.host_allowed("127.0.0.1:8080", 8080));
  EXPECT_TRUE(any.origin_allowed("http://10.1.2.3:8080"));
  // an IP literal the server does not listen on is as foreign as a name
  for (const char* host : {"10.1.2.4:8080", "203.0.113.7:8080", "[fe80::2]:8080",
                           "evil.example:8080", "10.1.2:8080", "0.0.0.0:8080"}) {
    EXPECT_FALSE(any.host_allowed(host, 8080)) << host;
  }
  EXPECT_FALSE(any.origin_allowed("http://203.0.113.7:8080"));
  EXPECT_EQ(any.page_origin(), "http://127.0.0.1:8080");
  // the addresses count only for a wildcard bind
  const HostPolicy loopback("127.0.0.1", 8080, 8081, {"10.1.2.3"});
  EXPECT_FALSE(loopback.host_allowed("10.1.2.3:8080", 8080));

  const HostPolicy v6("::1", 8080, 8081);
  EXPECT_TRUE(v6.host_allowed("[::1]:8080", 8080));
  EXPECT_EQ(v6.page_origin(), "http://[::1]:8080");
}

TEST(HostPolicy, OriginMustBeOneOfOurPagesExactly) {
  const HostPolicy p("127.0.0.1", 8080, 8081);
  for (const char* origin :
       {"http://127.0.0.1:8080", "http://localhost:8080", "http://[::1]:8080"}) {
    EXPECT_TRUE(p.origin_allowed(origin)) << origin;
  }
  for (const char* origin :
       {"https://127.0.0.1:8080", "http://127.0.0.1:8081", "http://127.0.0.1:8080/",
        "http://127.0.0.1", "http://LOCALHOST:8080", "http://evil.example:8080",
        "http://127.0.0.1:8080.evil.example", "null", "", "127.0.0.1:8080"}) {
    EXPECT_FALSE(p.origin_allowed(origin)) << origin;
  }
}

TEST(HostPolicy, HostNameDropsPortCaseAndTrailingDot) {
  EXPECT_EQ(HostPolicy::host_name("LocalHost.:8080"), "localhost");
  EXPECT_EQ(HostPolicy::host_name("[::1]:8081"), "[::1]");
  EXPECT_EQ(HostPolicy::host_name("no-port"), "");
}

TEST(Security, LoopbackAndWildcardAddresses) {
  for (const char* a :
       {"127.0.0.1", "127.1.2.3", "::1", "[::1]", "::ffff:127.0.0.1", "::FFFF:127.0.0.2"}) {
    EXPECT_TRUE(server::is_loopback_address(a)) << a;
  }
  for (const char* a :
       {"128.0.0.1", "10.0.0.1", "127.0.0.1.evil", "127.0.0", "localhost", "::2", ""}) {
    EXPECT_FALSE(server::is_loopback_address(a)) << a;
  }
  for (const char* a : {"0.0.0.0", "::", "[::]"}) EXPECT_TRUE(server::is_wildcard_address(a)) << a;
  EXPECT_FALSE(server::is_wildcard_address("127.0.0.1"));
  for (const char* h : {"localhost", "LOCALHOST", "127.0.0.1", "::1"})
    EXPECT_TRUE(server::is_loopback_host(h)) << h;
  for (const char* h : {"0.0.0.0", "example.com", "192.168.1.5"})
    EXPECT_FALSE(server::is_loopback_host(h)) << h;
}

TEST(Security, TokensCompareByContentAndLength) {
  const std::string token(32, 'a');
  EXPECT_TRUE(server::tokens_equal(token, std::string(32, 'a')));
  EXPECT_TRUE(server::tokens_equal("", ""));
  EXPECT_FALSE(server::tokens_equal(token, "b" + std::string(31, 'a')));
  EXPECT_FALSE(server::tokens_equal(token, std::string(31, 'a') + "b"));
  EXPECT_FALSE(server::tokens_equal(token, std::string(31, 'a')));
  EXPECT_FALSE(server::tokens_equal(token, token + "a"));
}

TEST(Security, RandomIdsAre128BitsOfLowercaseHex) {
  const std::string a = server::random_hex(16);
  const std::string b = server::random_hex(16);
  EXPECT_EQ(a.size(), 32u);
  EXPECT_TRUE(server::is_valid_id(a)) << a;
  EXPECT_NE(a, b);
  EXPECT_EQ(server::random_hex(0), "");
  EXPECT_FALSE(server::is_valid_id(std::string(31, 'a')));
  EXPECT_FALSE(server::is_valid_id(std::string(33, 'a')));
  EXPECT_FALSE(server::is_valid_id(std::string(32, 'A')));
  EXPECT_FALSE(server::is_valid_id(std::string(31, 'a') + "g"));
  EXPECT_FALSE(server::is_valid_id("../" + std::string(29, 'a')));
}

class StaticPathTest : public ::testing::Test {
 protected:
  void SetUp() override {
    base_ = fs::temp_directory_path() / ("pindrag-security-test-" + std::to_string(::getpid()));
    fs::remove_all(base_);
    root_ = base_ / "web";
    fs::create_directories(root_ / "js");
    fs::create_directories(root_ / ".hidden");
    fs::create_directories(root_ / "node_modules");
    fs::create_directories(root_ / "dir");
    std::ofstream(root_ / "index.html") << "page";
    std::ofstream(root_ / "js" / "main.js") << "script";
    std::ofstream(root_ / ".hidden" / "file") << "hidden";
    std::ofstream(root_ / "node_modules" / "x.js") << "module";
    std::ofstream(base_ / "secret.txt") << "secret";
    fs::create_symlink(base_ / "secret.txt", root_ / "link_out.txt");
    fs::create_symlink(root_ / "js" / "main.js", root_ / "link_in.js");
  }
  void TearDown() override {
    std::error_code ec;
    fs::remove_all(base_, ec);
  }
  // The refusal reason for `path` ("" when it resolves).
  std::string why(std::string_view path,
                  const std::vector<std::string>& forbidden = {"node_modules"}) {
    std::string reason;
    const auto resolved = server::resolve_static_path(root_, path, forbidden, &reason);
    return resolved ? "" : reason;
  }

  fs::path base_, root_;
};

TEST_F(StaticPathTest, FilesInsideTheRootResolveToTheirCanonicalPath) {
  const std::vector<std::string> forbidden{"node_modules"};
  EXPECT_EQ(server::resolve_static_path(root_, "/index.html", forbidden),
            fs::canonical(root_ / "index.html"));
  EXPECT_EQ(server::resolve_static_path(root_, "js/main.js", forbidden),
            fs::canonical(root_ / "js/main.js"));
  // a symlink that stays inside is followed
  EXPECT_EQ(server::resolve_static_path(root_, "/link_in.js", forbidden),
            fs::canonical(root_ / "js/main.js"));
  // a forbidden segment is only forbidden when listed
  EXPECT_EQ(server::resolve_static_path(root_, "/node_modules/x.js", {}),
            fs::canonical(root_ / "node_modules/x.js"));
}

TEST_F(StaticPathTest, EscapesAndOddPathsAreRefusedWithAReason) {
  EXPECT_EQ(why("/js/../index.html"), "the path has an empty, '.' or '..' segment");
  EXPECT_EQ(why("/js//main.js"), "the path has an empty, '.' or '..' segment");
  EXPECT_EQ(why("/./index.html"), "the path has an empty, '.' or '..' segment");
  EXPECT_EQ(why("/.hidden/file"), "the path names a hidden file");
  EXPECT_EQ(why("/node_modules/x.js"), "the path enters node_modules");
  EXPECT_EQ(why("/js\\main.js"), "the path holds a backslash");
  EXPECT_EQ(why(std::string_view("/index.html\0.js", 15)), "the path holds a NUL byte");
  EXPECT_EQ(why("//etc/passwd"), "the path is absolute");
  EXPECT_EQ(why("/"), "the path is empty");
  EXPECT_EQ(why("/dir"), "not a regular file");
  EXPECT_EQ(why("/missing.txt"), "no such file");
  EXPECT_EQ(why("/link_out.txt"), "the path leaves the static root");
  std::string reason;
  EXPECT_FALSE(server::resolve_static_path(base_ / "nowhere", "/index.html", {}, &reason));
  EXPECT_EQ(reason, "the static root does not exist");
}

TEST(Security, SafeFileNamesKeepOnlyPlainCharacters) {
  EXPECT_EQ(server::safe_file_name("human48", "x"), "human48");
  EXPECT_EQ(server::safe_file_name("walk cycle\"v2\".bvh", "x"), "walk_cycle_v2_.bvh");
  const std::string traversal = server::safe_file_name("../../etc/passwd", "x");
  EXPECT_EQ(traversal.find('/'), std::string::npos);
  EXPECT_NE(traversal.front(), '.');
  EXPECT_EQ(server::safe_file_name(".profile", "x"), "profile");
  EXPECT_EQ(server::safe_file_name("", "fallback"), "fallback");
  EXPECT_EQ(server::safe_file_name("///", "fallback"), "fallback");
  EXPECT_EQ(server::safe_file_name(std::string(100, 'a'), "x"), std::string(64, 'a'));
}

}  // namespace
