// Tests of GET /api/sessions/{id}/export (server/http_routes.cpp) over real sockets: a character
// uploaded as BVH exports in its own unit and per-joint orders by default, `units` and `order`
// change them, bad values are refused naming the parameter, and a restarted server still
// exports the same file; glTF and GLB exports of a character without a skinned mesh carry its
// shapes as a mesh with a material.
#include "tests/server/server_fixture.hpp"

#include <string>
#include <vector>

#include "io/bvh.hpp"
#include "tests/io/gltf_reader.hpp"

namespace {

using server_test::json;
using server_test::ServerTest;

// A BVH in centimetres (about 170 tall) with a different rotation order on each joint.
constexpr const char* kCentimetres =
    "HIERARCHY\nROOT Hips\n{\nOFFSET 0 0 0\n"
    "CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation\n"
    "JOINT Chest\n{\nOFFSET 0 85.5 -1.25\nCHANNELS 3 Zrotation Yrotation Xrotation\n"
    "End Site\n{\nOFFSET 0 80.25 0\n}\n}\n}\nMOTION\nFrames: 3\nFrame Time: 0.01\n"
    "1.5 90 2 10 20 30 40 -50 60\n2 91 3 11 21 31 41 -51 61\n2.5 92 4 12 22 32 42 -52 62\n";

class ExportRouteTest : public ServerTest {
 protected:
  Created upload_bvh() {
    httplib::MultipartFormDataItems items{{"character", kCentimetres, "cm.bvh", "text/plain"}};
    const auto res = http().Post("/api/sessions", {{"Origin", origin()}}, items);
    EXPECT_TRUE(res && res->status == 201) << (res ? res->body : "no reply");
    const json j = json::parse(res->body);
    return {j.at("id"), j.at("token")};
  }
  httplib::Result get_export(const Created& s, const std::string& query) {
    return http().Get("/api/sessions/" + s.id + "/export?" + query, {{"X-Session-Token", s.token}});
  }
  io::BvhDocument exported(const Created& s, const std::string& query) {
    const auto res = get_export(s, query);
    EXPECT_TRUE(res && res->status == 200) << (res ? res->body : "no reply");
    return io::parse_bvh(res ? res->body : "", "export?" + query);
  }
};

std::vector<std::string> orders(const io::BvhDocument& doc) {
  std::vector<std::string> out;
  for (const io::BvhNode& node : doc.nodes) {
    if (node.is_end_site()) continue;
    std::string order;
    for (io::BvhChannel c : node.channels) {
      if (io::is_rotation(c)) order += static_cast<char>('X' + io::channel_axis(c));
    }
    out.push_back(order);
  }
  return out;
}

TEST_F(ExportRouteTest, ABvhCharacterExportsInItsOwnUnitAndOrders) {
  const Created s = upload_bvh();
  const io::BvhDocument source = io::parse_bvh(kCentimetres, "cm.bvh");
  const io::BvhDocument d = exported(s, "format=bvh");
  EXPECT_EQ(orders(d), (std::vector<std::string>{"ZXY", "ZYX"}));
  ASSERT_EQ(d.nodes.size(), source.nodes.size());
  for (std::size_t k = 0; k < d.nodes.size(); ++k) {
    EXPECT_TRUE(d.nodes[k].offset.isApprox(source.nodes[k].offset, 1e-9)) << k;
  }
  // the page stands the figure (hips 0.9 m up, nothing below them) on the ground, and the export
  // is what the page shows: the root's height lowered by one amount in every frame, every other
  // channel as in the file
  ASSERT_EQ(d.values.size(), source.values.size());
  const std::size_t channels = 9;  // per frame: the root's 6 and the chest's 3
  const double lowered = source.values[1] - d.values[1];
  EXPECT_GT(lowered, 0.0);
  EXPECT_LT(lowered, 90.0);
  for (std::size_t k = 0; k < d.values.size(); ++k) {
    const double expected = source.values[k] - (k % channels == 1 ? lowered : 0.0);
    EXPECT_NEAR(d.values[k], expected, 1e-6) << "value " << k;
  }
  // "source" spelled out is the default
  EXPECT_EQ(get_export(s, "format=bvh&units=source&order=source")->body,
            get_export(s, "format=bvh")->body);

  const io::BvhDocument m = exported(s, "format=bvh&units=m&order=XYZ");
  EXPECT_EQ(orders(m), (std::vector<std::string>{"XYZ", "XYZ"}));
  EXPECT_NEAR(m.nodes[1].offset.y(), 0.855, 1e-9);
  EXPECT_NEAR(m.frame(0)[1], 0.9 - lowered / 100, 1e-9);
  const io::BvhDocument cm = exported(s, "format=bvh&units=cm&order=yxz");
  EXPECT_EQ(orders(cm), (std::vector<std::string>{"YXZ", "YXZ"}));
  EXPECT_NEAR(cm.nodes[1].offset.y(), 85.5, 1e-9);
}

TEST_F(ExportRouteTest, BadUnitsOrOrderAreRefusedNamingTheParameter) {
  const Created s = upload_bvh();
  const auto error = [&](const std::string& query) {
    const auto res = get_export(s, query);
    EXPECT_TRUE(res && res->status == 400) << query;
    return res ? json::parse(res->body).value("error", "") : "";
  };
  EXPECT_EQ(error("format=bvh&units=ft"), "units: 'ft' (rule: one of m, cm, source)");
  EXPECT_EQ(error("format=bvh&order=XXZ"),
            "order: 'XXZ' (rule: one of XYZ, XZY, YXZ, YZX, ZXY, ZYX, source)");
  EXPECT_EQ(error("format=glb&order=XYZ"), "order: needs format=bvh");
  EXPECT_EQ(error("format=gltf&units=cm"), "units: needs format=bvh");
  // other characters have no BVH source: metres and ZXY, unless asked otherwise
  const Created human = create_session();
  EXPECT_EQ(orders(exported(human, "format=bvh&order=source"))[0], "ZXY");
  EXPECT_EQ(orders(exported(human, "format=bvh&order=ZYX"))[0], "ZYX");
}

TEST_F(ExportRouteTest, GltfAndGlbOfADefaultSessionCarryItsShapesAsAMeshWithAMaterial) {
  const Created s = create_session();
  for (const std::string format : {"glb", "gltf"}) {
    const auto res = get_export(s, "format=" + format);
    ASSERT_TRUE(res && res->status == 200) << (res ? res->body : "no reply");
    std::vector<std::string> errors;
    const gltf_test::Document doc =
        format == "glb" ? gltf_test::parse_glb(
                              std::vector<std::uint8_t>(res->body.begin(), res->body.end()), errors)
                        : gltf_test::parse_gltf(res->body, errors);
    gltf_test::check_layout(doc, errors);
    for (const std::string& e : errors) ADD_FAILURE() << format << ": " << e;
    const json& j = doc.json;
    ASSERT_EQ(j["meshes"].size(), 1u) << format;
    EXPECT_EQ(j["meshes"][0]["name"], "shapes");
    const json& prim = j["meshes"][0]["primitives"][0];
    ASSERT_TRUE(prim.contains("material")) << format;
    ASSERT_EQ(j["materials"].size(), 1u) << format;
    EXPECT_EQ(j["materials"][0]["pbrMetallicRoughness"]["baseColorFactor"].size(), 4u);
    EXPECT_GT(j["accessors"][prim["attributes"]["POSITION"].get<int>()]["count"].get<int>(), 0);
    EXPECT_TRUE(prim["attributes"].contains("JOINTS_0")) << format;
    int skinned_nodes = 0;
    for (const json& n : j["nodes"])
      skinned_nodes += n.contains("mesh") && n.value("skin", -1) == 0;
    EXPECT_EQ(skinned_nodes, 1) << format;
  }
}

TEST_F(ExportRouteTest, ARestartedServerExportsTheSameFile) {
  const Created s = upload_bvh();
  const std::string before = get_export(s, "format=bvh")->body;
  restart();
  ASSERT_EQ(server_->restored_sessions(), 1);
  EXPECT_EQ(get_export(s, "format=bvh")->body, before);
}

}  // namespace
