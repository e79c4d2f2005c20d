// Tests for server/upload_resources.hpp: the files sent beside a .gltf upload.
#include "server/upload_resources.hpp"

#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "server/uploads.hpp"

namespace {

using server::UploadResource;

// the status and message of the refusal, or {0, ""} when the resources are taken
std::pair<int, std::string> resources_refusal(const std::string& gltf,
                                              const std::vector<UploadResource>& resources,
                                              const server::UploadCaps& caps = {},
                                              const std::string& ext = ".gltf") {
  try {
    server::check_upload_resources("character", "a.gltf", ext, gltf, resources, caps);
  } catch (const server::UploadError& e) {
    return {e.status, e.what()};
  }
  return {0, ""};
}

const std::string kTwoBuffers =
    R"({"buffers": [{"uri": "data:application/octet-stream;base64,AAAA", "byteLength": 3},
                    {"uri": "skin%20weights.bin", "byteLength": 4}, {"byteLength": 8}]})";

TEST(UploadResources, EmbeddedAndChunkBuffersNeedNothingAFileBufferMustBeSent) {
  EXPECT_EQ(resources_refusal(R"({"buffers": [{"uri": "data:,x"}, {"byteLength": 1}]})", {}).first,
            0);
  const auto [status, message] = resources_refusal(kTwoBuffers, {});
  EXPECT_EQ(status, 422);
  EXPECT_NE(message.find("references the buffer \"skin_weights.bin\", which was not sent"),
            std::string::npos)
      << message;
  // a buffer in another folder cannot be sent beside the file
  EXPECT_NE(resources_refusal(R"({"buffers": [{"uri": "bin/a.bin"}]})", {{"a.bin", "x"}})
                .second.find("in another folder"),
            std::string::npos);
  // only a buffer's own "uri": not an image's, an extension's or one elsewhere
  EXPECT_EQ(resources_refusal(R"({"uri": "a.bin", "images": [{"uri": "skin.png"}],
                                  "buffers": [{"byteLength": 1, "extras": {"uri": "b.bin"}}],
                                  "extensions": {"buffers": [{"uri": "c.bin"}]}})",
                              {})
                .first,
            0);
  // text that is not glTF JSON is the importer's to name
  EXPECT_EQ(resources_refusal("not json", {}).first, 0);
}

TEST(UploadResources, AnEncodedUriIsStoredUnderItsNameAndUnderItsUri) {
  const std::vector<UploadResource> sent = {{"skin weights.bin", "1234"}, {"skin.png", "png"}};
  const std::vector<server::StoredResource> stored =
      server::check_upload_resources("character", "a.gltf", ".gltf", kTwoBuffers, sent, {});
  ASSERT_EQ(stored.size(), 3u);
  EXPECT_EQ(stored[0].name, "skin weights.bin");
  EXPECT_EQ(stored[1].name, "skin.png");
  EXPECT_EQ(stored[2].name, "skin%20weights.bin");
  EXPECT_EQ(stored[2].resource, &sent[0]);
}

TEST(UploadResources, NamesCountsAndSizesHaveRules) {
  const std::vector<std::string> bad_names = {
      "",       "../a.bin", "a/b.bin",     "a\\b.bin",
      ".a.bin", "a\nb.bin", "UPLOAD.gltf", std::string(256, 'a')};
  for (const std::string& bad : bad_names) {
    const auto [status, message] = resources_refusal(kTwoBuffers, {{bad, "x"}});
    EXPECT_EQ(status, 400) << bad;
    EXPECT_NE(message.find("is not a plain file name"), std::string::npos) << message;
  }
  EXPECT_NE(resources_refusal(kTwoBuffers, {{"skin weights.bin", "x"}, {"skin weights.bin", "y"}})
                .second.find("is sent twice"),
            std::string::npos);
  std::vector<UploadResource> many(server::kMaxUploadResources + 1);
  for (std::size_t i = 0; i < many.size(); ++i) many[i] = {"f" + std::to_string(i) + ".png", "x"};
  EXPECT_EQ(resources_refusal(kTwoBuffers, many).first, 400);
  server::UploadCaps caps;
  caps.gltf = kTwoBuffers.size() + 3;
  const auto [status, message] =
      resources_refusal(kTwoBuffers, {{"skin weights.bin", "1234"}}, caps);
  EXPECT_EQ(status, 413);
  EXPECT_NE(message.find("(set by pindrag serve --max-upload-gltf)"), std::string::npos) << message;
  // only a file that can reference others brings them; its stored name is its own
  EXPECT_EQ(resources_refusal("", {{"a.bin", "x"}}, {}, ".bvh").first, 400);
  EXPECT_EQ(resources_refusal("", {}, {}, ".bvh").first, 0);
  EXPECT_EQ(resources_refusal("", {{"skin.png", "x"}}, {}, ".fbx").first, 0);
  EXPECT_NE(resources_refusal("", {{"Upload.fbx", "x"}}, {}, ".fbx")
                .second.find("not upload.fbx, the name the upload is stored under"),
            std::string::npos);
}

}  // namespace
