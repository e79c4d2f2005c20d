// Tests for io/json_reader.hpp and io/json_parse.hpp: the bounded parser (syntax errors with line
// and column, duplicate keys, nesting and value caps, size cap) and the field reader (messages
// that name the field as a JSON pointer in each style, range-checked numbers that never wrap,
// unknown keys, collecting every error of a document).
#include "io/json_reader.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <nlohmann/json.hpp>
#include <string>

#include "io/read_file.hpp"

namespace {

namespace fs = std::filesystem;
using io::JsonField;
using io::JsonFieldError;
using io::JsonFields;
using io::JsonParseError;
using io::JsonReader;
using io::JsonStyle;
using io::JsonWording;
using nlohmann::json;

// The message of the JsonFieldError that `read` throws ("" when none).
template <typename Read>
std::string field_error(Read&& read) {
  try {
    read();
  } catch (const JsonFieldError& e) {
    return e.what();
  }
  return "";
}

// The JsonParseError that parsing `text` throws.
JsonParseError parse_error(const std::string& text, const io::JsonLimits& limits = {}) {
  try {
    io::parse_json(text, "t.json", limits);
  } catch (const JsonParseError& e) {
    return e;
  }
  ADD_FAILURE() << "no JsonParseError for " << text.substr(0, 80);
  return JsonParseError(JsonParseError::Kind::kSyntax, "", 0, 0, "", "");
}

// --------------------------------------------------------------------------------------------
// parsing

TEST(JsonParse, SyntaxErrorsGiveLineAndColumnInCharacters) {
  const JsonParseError e = parse_error("{\n  \"a\": [1,\n  tru]\n}");
  EXPECT_EQ(e.kind, JsonParseError::Kind::kSyntax);
  EXPECT_EQ(e.line, 3u);
  EXPECT_EQ(e.column, 6u);  // the ']' after "tru"
  EXPECT_EQ(std::string(e.what()).rfind("t.json: line 3, column 6: syntax error", 0), 0u)
      << e.what();
  // 'é' is two bytes and one column
  EXPECT_EQ(parse_error("[\"é\", x]").column, 7u);
  const JsonParseError empty = parse_error("");
  EXPECT_EQ(std::string(empty.what()),
            "t.json: line 1, column 1: the file is empty (rule: a JSON value)");
}

TEST(JsonParse, DuplicateKeysAreRefusedNamingThePointer) {
  const JsonParseError e = parse_error(R"({"links": [{"name": "a", "name": "b"}]})");
  EXPECT_EQ(e.kind, JsonParseError::Kind::kDuplicateKey);
  EXPECT_EQ(e.pointer, "/links/0/name");
  EXPECT_EQ(std::string(e.what()),
            "t.json: /links/0/name: duplicate key (rule: the keys of an object are unique)");
  // the same key in different objects is fine
  EXPECT_NO_THROW(io::parse_json(R"({"a": {"x": 1}, "b": {"x": 1}})", "t.json"));
}

TEST(JsonParse, NestingIsCappedWithoutRecursion) {
  const JsonParseError e = parse_error(R"({"a": [[[1]]]})", {.max_depth = 3});
  EXPECT_EQ(e.kind, JsonParseError::Kind::kDepth);
  EXPECT_EQ(e.pointer, "/a/0/0");
  EXPECT_EQ(e.line, 1u);
  EXPECT_EQ(e.column, 9u);  // the bracket that opens the fourth level
  EXPECT_NE(std::string(e.what()).find("nest deeper than 3 levels (rule: at most 3)"),
            std::string::npos);
  EXPECT_NO_THROW(io::parse_json(R"({"a": [[1]]})", "t.json", {.max_depth = 3}));
  // a million open brackets: refused at the default cap, not a stack overflow
  const JsonParseError deep = parse_error(std::string(1000000, '['));
  EXPECT_EQ(deep.kind, JsonParseError::Kind::kDepth);
  EXPECT_EQ(deep.column, static_cast<std::size_t>(io::kMaxJsonDepth) + 1);
}

TEST(JsonParse, ValueCountIsCapped) {
  // the array itself and five numbers: six values
  const JsonParseError e = parse_error("[1, 2, 3, 4, 5]", {.max_values = 5});
  EXPECT_EQ(e.kind, JsonParseError::Kind::kValues);
  EXPECT_EQ(e.pointer, "/4");
  EXPECT_EQ(std::string(e.what()),
            "t.json: /4: the document holds more than 5 values (rule: at most 5)");
  EXPECT_NO_THROW(io::parse_json("[1, 2, 3, 4]", "t.json", {.max_values = 5}));
}

TEST(JsonParse, SizeIsCappedForTextAndFiles) {
  const JsonParseError e = parse_error("[1, 2]", {.max_bytes = 5});
  EXPECT_EQ(e.kind, JsonParseError::Kind::kSize);
  EXPECT_EQ(std::string(e.what()), "t.json: text is 6 bytes (rule: at most 5 bytes)");

  const fs::path path =
      fs::temp_directory_path() / ("pindrag_json_reader_" + std::to_string(::getpid()) + ".json");
  std::ofstream(path) << R"({"a": [1, 2, 3]})";
  EXPECT_EQ(io::read_json_file(path.string())["a"][2], 3);
  try {
    io::read_json_file(path.string(), {.max_bytes = 8}, "a test file");
    ADD_FAILURE() << "no FileError";
  } catch (const io::FileError& f) {
    EXPECT_EQ(std::string(f.what()),
              path.string() + ": file is 16 bytes (rule: a test file is at most 8 bytes)");
  }
  fs::remove(path);
  EXPECT_THROW(io::read_json_file(path.string()), io::FileError);
}

// --------------------------------------------------------------------------------------------
// fields

TEST(JsonField, PointersAreBuiltAndEscapedAsRfc6901) {
  const json doc = json::parse(R"({"a/b~c": [10, {"x": null}]})");
  const JsonField root(doc);
  EXPECT_EQ(root.pointer(), "");
  const JsonField x = root["a/b~c"][1]["x"];
  EXPECT_EQ(x.pointer(), "/a~1b~0c/1/x");
  EXPECT_TRUE(x.exists());
  EXPECT_FALSE(x.given());  // null counts as left out
  EXPECT_EQ(root["a/b~c"].size(), 2u);
  // absent members and elements can still be named
  EXPECT_FALSE(root["nope"]["deeper"]);
  EXPECT_EQ(root["nope"]["deeper"].pointer(), "/nope/deeper");
  EXPECT_FALSE(root["a/b~c"][5]);
  EXPECT_EQ(*root["a/b~c"][0], 10);
}

TEST(JsonReader, MessagesNameTheFieldInEachStyle) {
  const json doc = json::parse(R"({"links": [{}, {}, {}, {"inertial": {"mass": "heavy"}}],
                                    "link": 3, "gains": {"drag": "x"}})");
  const JsonField root(doc);
  const JsonField mass = root["links"][3]["inertial"]["mass"];
  EXPECT_EQ(field_error([&] { JsonFields().number(mass); }),
            "/links/3/inertial/mass: expected a number, got a string");
  JsonFields request(JsonStyle{.root = "/", .wording = JsonWording::kRequest});
  EXPECT_EQ(field_error([&] { request.number(mass); }),
            "/links/3/inertial/mass: expected a number, got string");
  EXPECT_EQ(field_error([&] { request.object(JsonField(&doc["link"], "")); }),
            "/: expected an object, got number");
  JsonFields message(JsonStyle{.base = "pin", .dotted = true});
  EXPECT_EQ(field_error([&] { message.string(root["link"]); }),
            "pin.link: expected a string, got a number");
  EXPECT_EQ(field_error([&] { message.vector3(root["target"]); }),
            "pin.target: missing (rule: required)");
  JsonFields section(JsonStyle{.base = "settings"});
  EXPECT_EQ(field_error([&] { section.number(root["gains"]["drag"]); }),
            "settings/gains/drag: expected a number, got a string");
  EXPECT_EQ(field_error([&] { JsonFields().object(JsonField(&doc["link"], "")); }),
            "document root: expected an object, got a number");
  // the error carries its parts
  try {
    JsonFields().number(mass);
  } catch (const JsonFieldError& e) {
    EXPECT_EQ(e.pointer, "/links/3/inertial/mass");
    EXPECT_EQ(e.location, "/links/3/inertial/mass");
    EXPECT_EQ(e.rule, "expected a number, got a string");
  }
}

TEST(JsonReader, IntegersAreRangeCheckedNeverWrapped) {
  const json doc = json::parse(
      R"({"big": 4294967297, "huge": 18446744073709551615, "neg": -1, "frac": 3.5, "exp": 1e2,
          "ok": 7, "text": "7"})");
  const JsonField root(doc);
  JsonFields f;
  constexpr std::int64_t kIntMin = std::numeric_limits<int>::min();
  constexpr std::int64_t kIntMax = std::numeric_limits<int>::max();
  // 4294967297 would be 1 as a 32-bit int
  EXPECT_EQ(field_error([&] { f.integer(root["big"], kIntMin, kIntMax); }),
            "/big: 4294967297 is out of range (rule: an integer in [-2147483648, 2147483647])");
  EXPECT_EQ(f.integer(root["big"], 0, std::numeric_limits<std::int64_t>::max()), 4294967297);
  // above INT64_MAX: refused, not read as a negative number
  EXPECT_NE(field_error([&] {
              f.integer(root["huge"], std::numeric_limits<std::int64_t>::min(),
                        std::numeric_limits<std::int64_t>::max());
            }).find("/huge: 18446744073709551615 is out of range"),
            std::string::npos);
  EXPECT_EQ(field_error([&] { f.integer(root["neg"], 0, 10); }),
            "/neg: -1 is out of range (rule: an integer in [0, 10])");
  EXPECT_EQ(field_error([&] { f.integer(root["frac"], 0, 10); }),
            "/frac: expected an integer, got a number with a fraction or an exponent");
  EXPECT_NE(field_error([&] { f.integer(root["exp"], 0, 1000); }), "");
  EXPECT_EQ(field_error([&] { f.integer(root["text"], 0, 10); }),
            "/text: expected an integer, got a string");
  EXPECT_EQ(f.integer(root["ok"], 0, 10), 7);
  EXPECT_EQ(f.integer_or(root["absent"], 5, 0, 10), 5);
}

TEST(JsonReader, NumbersAreFiniteAndInRange) {
  json doc = json::parse(R"({"x": 2.5, "v": [1, 2, 3], "short": [1, 2], "nul": null})");
  doc["nan"] = std::numeric_limits<double>::quiet_NaN();
  const JsonField root(doc);
  JsonFields f;
  EXPECT_EQ(f.number(root["x"], {.lo = 0, .hi = 3}), 2.5);
  EXPECT_EQ(field_error([&] { f.number(root["x"], {.lo = 0, .hi = 1}); }),
            "/x: 2.5 is out of range (rule: a number in [0, 1])");
  EXPECT_EQ(field_error([&] { f.number(root["x"], {.lo = 3}); }),
            "/x: 2.5 is out of range (rule: a number >= 3)");
  EXPECT_EQ(field_error([&] { f.number(root["nan"]); }), "/nan: number is not finite");
  EXPECT_EQ(field_error([&] { f.number_or(root["nul"], 1.0); }),
            "/nul: expected a number, got null");  // a null is given, not absent
  EXPECT_EQ(f.number_or(root["absent"], 1.5), 1.5);
  EXPECT_EQ(f.vector3(root["v"]), Eigen::Vector3d(1, 2, 3));
  EXPECT_EQ(field_error([&] { f.vector3(root["v"], {.hi = 2.5}); }),
            "/v/2: 3 is out of range (rule: a number <= 2.5)");
  EXPECT_EQ(field_error([&] { f.vector3(root["short"]); }),
            "/short: expected an array of 3 numbers, got an array of 2 values");
}

TEST(JsonReader, QuaternionsAreUnitWithinTheTolerance) {
  const json doc = json::parse(
      R"({"unit": [1, 0, 0, 0], "near": [1.0005, 0, 0, 0], "far": [2, 0, 0, 0],
          "zero": [0, 0, 0, 0], "short": [1, 0, 0]})");
  const JsonField root(doc);
  JsonFields f;
  EXPECT_EQ(f.quaternion(root["unit"]).coeffs(), Eigen::Quaterniond::Identity().coeffs());
  EXPECT_NEAR(f.quaternion(root["near"]).norm(), 1.0, 1e-15);  // normalized
  EXPECT_EQ(field_error([&] { f.quaternion(root["far"]); }),
            "/far: quaternion [w, x, y, z] has norm 2 (rule: unit length within 0.001)");
  JsonFields request(JsonStyle{.wording = JsonWording::kRequest});
  EXPECT_EQ(field_error([&] { request.quaternion(root["far"]); }),
            "/far: quaternion norm is 2 (rule: unit length within 0.001)");
  EXPECT_EQ(field_error([&] { request.quaternion(root["short"]); }),
            "/short: expected an array of 4 numbers [w, x, y, z]");
  // any direction, normalized; only the zero quaternion has none
  const double any = std::numeric_limits<double>::infinity();
  EXPECT_EQ(f.quaternion(root["far"], any).coeffs(), Eigen::Quaterniond::Identity().coeffs());
  EXPECT_EQ(field_error([&] { f.quaternion(root["zero"], any); }),
            "/zero: quaternion [w, x, y, z] has norm 0 (rule: a quaternion of nonzero length)");
}

TEST(JsonReader, UnknownKeysWarnOrAreRefused) {
  const json doc = json::parse(R"({"dt": 1, "efects": true, "settings": {"dampign": 1}})");
  const JsonField root(doc);
  JsonReader r;
  r.warn_unknown_keys(root, {"dt", "settings"});
  r.warn_unknown_keys(root["settings"], {"damping"});
  EXPECT_EQ(r.warnings(), (std::vector<std::string>{"/efects: unknown key (ignored)",
                                                    "/settings/dampign: unknown key (ignored)"}));
  EXPECT_EQ(field_error([&] {
              r.refuse_unknown_keys(root, {"dt", "settings"});
            }),
            "/efects: unknown key (rule: one of dt, settings)");
  std::vector<std::string> seen;
  JsonFields f;
  f.set_warning_sink([&](const std::string& w) { seen.push_back(w); });
  f.warn_unknown_keys(root, {"dt", "settings"});
  EXPECT_EQ(seen, std::vector<std::string>{"/efects: unknown key (ignored)"});
  EXPECT_TRUE(f.warnings().empty());
}

TEST(JsonReader, CollectsEveryErrorOfADocument) {
  const json doc = json::parse(R"({"a": "x", "b": [1, "y", "z"], "c": 4294967297})");
  const JsonField root(doc);
  JsonReader r(JsonStyle{}, JsonReader::OnError::kCollect);
  EXPECT_FALSE(r.number(root["a"]));
  EXPECT_FALSE(r.vector<3>(root["b"]));
  EXPECT_FALSE(r.integer(root["c"], 0, 100));
  EXPECT_FALSE(r.string(root["d"]));
  EXPECT_EQ(r.errors(), (std::vector<std::string>{
                            "/a: expected a number, got a string",
                            "/b/1: expected a number, got a string",
                            "/b/2: expected a number, got a string",
                            "/c: 4294967297 is out of range (rule: an integer in [0, 100])",
                            "/d: missing (rule: required)",
                        }));
}

}  // namespace
