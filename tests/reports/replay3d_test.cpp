// The 3D replay block: base64 against the RFC 4648 vectors, the 16-bit position quantisation
// against its error bound, the input checks, and the arrays in report.html decoded back (with
// a decoder of the test's own) against the input.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "fullarm/reports/replay3d.hpp"
#include "fullarm/reports/report.hpp"
#include "report_test_util.hpp"

namespace fullarm::reports {
namespace {

// Base64 to bytes by a lookup of each character (no code shared with the writer).
std::vector<unsigned char> fromBase64(const std::string& text) {
  const std::string alphabet = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::vector<unsigned char> bytes;
  std::uint32_t bits = 0;
  int count = 0;
  for (const char c : text) {
    if (c == '=') break;
    const std::size_t index = alphabet.find(c);
    EXPECT_NE(index, std::string::npos) << "not base64: " << c;
    bits = (bits << 6) | static_cast<std::uint32_t>(index);
    count += 6;
    if (count >= 8) {
      count -= 8;
      bytes.push_back(static_cast<unsigned char>((bits >> count) & 0xFFU));
    }
  }
  return bytes;
}

template <typename T>
std::vector<T> decodeArray(const nlohmann::json& value) {
  const std::vector<unsigned char> bytes = fromBase64(value.get<std::string>());
  EXPECT_EQ(bytes.size() % sizeof(T), 0U);
  std::vector<T> out(bytes.size() / sizeof(T));
  if (!out.empty()) std::memcpy(out.data(), bytes.data(), out.size() * sizeof(T));  // little-endian test machines
  return out;
}

// Two links over three frames, one box face of a mesh, one minimum, two events.
Replay3d sampleReplay() {
  Replay3d replay;
  replay.title = "Arm replay";
  replay.meshes.push_back(
      {"wall", {{0.0, 0.0, 0.0}, {1.0, 0.0, 0.0}, {1.0, 0.0, 2.0}, {0.0, 0.0, 2.0}}, {{0, 1, 2}, {0, 2, 3}}});
  replay.links = {{"upper", 0.05}, {"fore", 0.04}};
  replay.joints = {"SFE", "EB"};
  replay.torque_scale_nm = 10.0;
  replay.force_scale_n = 20.0;
  for (int f = 0; f < 3; ++f) {
    ReplayFrame frame;
    frame.t_s = 0.04 * f;
    frame.segments_m = {{0.0, 0.0, 0.0, 0.0, 0.0, -0.3}, {0.0, 0.0, -0.3, 0.1 * f, 0.2, -0.3}};
    frame.penetrating = {false, f == 2};
    frame.torques_nm = {1.5 * f, -0.25};
    if (f >= 1) frame.minima.push_back({{0.1, 0.2, -0.3}, {0.1, 0.0, -0.3}, 4.0 * f});
    replay.frames.push_back(std::move(frame));
  }
  replay.events = {{0.01, "start-up guard released", false}, {0.07, "trip: joint limit", true}};
  return replay;
}

TEST(ReplayBase64, MatchesTheRfc4648Vectors) {
  EXPECT_EQ(encodeBase64(""), "");
  EXPECT_EQ(encodeBase64("f"), "Zg==");
  EXPECT_EQ(encodeBase64("fo"), "Zm8=");
  EXPECT_EQ(encodeBase64("foo"), "Zm9v");
  EXPECT_EQ(encodeBase64("foob"), "Zm9vYg==");
  EXPECT_EQ(encodeBase64("fooba"), "Zm9vYmE=");
  EXPECT_EQ(encodeBase64("foobar"), "Zm9vYmFy");
  const std::string all_bytes = [] {
    std::string s;
    for (int b = 0; b < 256; ++b) s.push_back(static_cast<char>(b));
    return s;
  }();
  const std::vector<unsigned char> back = fromBase64(encodeBase64(all_bytes));
  ASSERT_EQ(back.size(), 256U);
  for (int b = 0; b < 256; ++b) EXPECT_EQ(back[static_cast<std::size_t>(b)], b);
}

TEST(ReplayQuantisation, ErrorIsAtMostHalfAStepPerAxis) {
  std::mt19937 random(7);
  std::uniform_real_distribution<double> coordinate(-2.5, 3.0);
  std::vector<std::array<double, 3>> vertices(500);
  for (auto& v : vertices) v = {coordinate(random), coordinate(random) * 0.01, coordinate(random) * 10.0};
  const QuantisedPositions q = quantisePositions(vertices);
  ASSERT_EQ(q.q.size(), vertices.size() * 3);
  for (std::size_t i = 0; i < vertices.size(); ++i) {
    for (std::size_t a = 0; a < 3; ++a) {
      const double back = q.origin_m[a] + q.q[i * 3 + a] * q.scale_m[a];
      EXPECT_LE(std::abs(back - vertices[i][a]), 0.5 * q.scale_m[a] * (1.0 + 1e-9)) << i << " axis " << a;
    }
  }
  // The box's corners land exactly on 0 and 65535.
  for (std::size_t a = 0; a < 3; ++a) {
    std::uint16_t low = 65535;
    std::uint16_t high = 0;
    for (std::size_t i = 0; i < vertices.size(); ++i) {
      low = std::min(low, q.q[i * 3 + a]);
      high = std::max(high, q.q[i * 3 + a]);
    }
    EXPECT_EQ(low, 0);
    EXPECT_EQ(high, 65535);
  }
}

TEST(ReplayQuantisation, AFlatAxisKeepsItsValue) {
  const QuantisedPositions q = quantisePositions({{1.0, 2.0, 3.0}, {4.0, 2.0, 3.0}});
  EXPECT_EQ(q.origin_m[1], 2.0);
  EXPECT_EQ(q.q[1], 0);
  EXPECT_EQ(q.q[4], 0);
  EXPECT_EQ(q.origin_m[1] + q.q[4] * q.scale_m[1], 2.0);
}

TEST(ReplayInput, BadReplaysAreRejectedNamingTheReplay) {
  const auto rejects = [](Replay3d replay, const std::string& expected) {
    Section section("s");
    try {
      section.addReplay3d(std::move(replay));
      ADD_FAILURE() << "accepted; expected an error containing: " << expected;
    } catch (const std::invalid_argument& error) {
      const std::string message = error.what();
      EXPECT_NE(message.find(expected), std::string::npos) << message;
    }
    EXPECT_TRUE(section.blocks().empty());
  };
  Replay3d r = sampleReplay();
  r.title.clear();
  rejects(r, "title");
  r = sampleReplay();
  r.links.clear();
  rejects(r, "Arm replay");
  r = sampleReplay();
  r.frames.clear();
  rejects(r, "at least one frame");
  r = sampleReplay();
  r.links[1].radius_m = 0.0;
  rejects(r, "link \"fore\" has radius 0");
  r = sampleReplay();
  r.frames[2].t_s = r.frames[1].t_s;
  rejects(r, "strictly increasing");
  r = sampleReplay();
  r.frames[1].segments_m.pop_back();
  rejects(r, "one per link");
  r = sampleReplay();
  r.frames[0].torques_nm.push_back(0.0);
  rejects(r, "one per joint");
  r = sampleReplay();
  r.meshes[0].triangles[1][2] = 4;
  rejects(r, "vertex index 4");
  r = sampleReplay();
  r.frames[1].minima[0].force_n = -1.0;
  rejects(r, "force -1");
  r = sampleReplay();
  r.frames[2].segments_m[0][4] = std::nan("");
  rejects(r, "finite");
  r = sampleReplay();
  r.force_scale_n = 0.0;
  rejects(r, "force_scale_n");
}

Report reportWith(const Replay3d& replay) {
  Report report("run", "Replay");
  report.setVerdict(true, "ok");
  report.addSection("3D").addReplay3d(replay);
  return report;
}

TEST(ReplayHtml, ArraysDecodeBackToTheInput) {
  const Replay3d replay = sampleReplay();
  const std::string html = reportWith(replay).html();
  const nlohmann::json data = nlohmann::json::parse(test::jsonDataBlock(html));
  ASSERT_TRUE(data["replays"].contains("replay-1"));
  const nlohmann::json& r = data["replays"]["replay-1"];
  EXPECT_NE(html.find("data-replay3d=\"replay-1\""), std::string::npos);
  EXPECT_EQ(r["frame_count"], 3);
  EXPECT_EQ(r["links"][1]["name"], "fore");
  EXPECT_EQ(r["links"][1]["radius_m"], 0.04);
  EXPECT_EQ(r["joints"], (nlohmann::json{"SFE", "EB"}));

  EXPECT_EQ(decodeArray<double>(r["t_f64"]), (std::vector<double>{0.0, 0.04, 0.08}));
  const std::vector<float> segments = decodeArray<float>(r["segments_f32"]);
  ASSERT_EQ(segments.size(), 3U * 2U * 6U);
  for (std::size_t f = 0; f < 3; ++f) {
    for (std::size_t l = 0; l < 2; ++l) {
      for (std::size_t c = 0; c < 6; ++c) {
        EXPECT_EQ(segments[(f * 2 + l) * 6 + c], static_cast<float>(replay.frames[f].segments_m[l][c]));
      }
    }
  }
  EXPECT_EQ(decodeArray<std::uint8_t>(r["penetrating_u8"]), (std::vector<std::uint8_t>{0, 0, 0, 0, 0, 1}));
  EXPECT_EQ(decodeArray<float>(r["torques_f32"]), (std::vector<float>{0.0F, -0.25F, 1.5F, -0.25F, 3.0F, -0.25F}));
  EXPECT_EQ(decodeArray<std::uint32_t>(r["minima_offsets_u32"]), (std::vector<std::uint32_t>{0, 0, 1, 2}));
  const std::vector<float> minima = decodeArray<float>(r["minima_f32"]);
  ASSERT_EQ(minima.size(), 14U);
  EXPECT_EQ(minima[1], 0.2F);
  EXPECT_EQ(minima[4], 0.0F);
  EXPECT_EQ(minima[6], 4.0F);
  EXPECT_EQ(minima[13], 8.0F);

  const nlohmann::json& mesh = r["meshes"][0];
  const std::vector<std::uint16_t> q = decodeArray<std::uint16_t>(mesh["positions_u16"]);
  ASSERT_EQ(q.size(), 12U);
  for (std::size_t v = 0; v < 4; ++v) {
    for (std::size_t a = 0; a < 3; ++a) {
      const double back = mesh["origin_m"][a].get<double>() + q[v * 3 + a] * mesh["scale_m"][a].get<double>();
      EXPECT_NEAR(back, replay.meshes[0].vertices_m[v][a], 1e-12);
    }
  }
  EXPECT_EQ(decodeArray<std::uint32_t>(mesh["indices_u32"]), (std::vector<std::uint32_t>{0, 1, 2, 0, 2, 3}));
  ASSERT_EQ(r["events"].size(), 2U);
  EXPECT_EQ(r["events"][1]["label"], "trip: joint limit");
  EXPECT_EQ(r["events"][1]["trip"], true);
}

TEST(ReplayHtml, ThreeJsIsInlinedOnlyWithAReplay) {
  const std::string banner = "three.js r" + std::string(threeVersion()).substr(2, 3);
  const std::string with = reportWith(sampleReplay()).html();
  EXPECT_NE(with.find(banner), std::string::npos);
  EXPECT_NE(with.find("the 3D replay with three.js " + std::string(threeVersion())), std::string::npos);
  Report plain("run", "No replay");
  plain.setVerdict(true, "ok");
  plain.addSection("text").addParagraph("nothing in 3D");
  const std::string without = plain.html();
  EXPECT_EQ(without.find(banner), std::string::npos);
  // The replay's code adds a few hundred kB, the scene a little more; the page without a replay
  // pays nothing for it.
  EXPECT_GT(with.size(), without.size() + 200'000U);
  // No network reference anywhere outside the scripts.
  for (const std::string& reference : test::loadingReferences(with)) {
    EXPECT_FALSE(test::isNetworkReference(reference)) << reference;
  }
}

TEST(SectionColumns, BlocksAreLaidOutInTheGivenColumns) {
  Report report("run", "Side by side");
  report.setVerdict(true, "ok");
  report.addSection("Two").setColumns(2).addParagraph("left").addParagraph("right");
  report.addSection("One").addParagraph("alone");
  const std::string html = report.html();
  EXPECT_EQ(test::countOccurrences(html, "<div class=\"columns columns-2\">"), 1U);
  EXPECT_EQ(test::countOccurrences(html, "<div class=\"column-cell\">"), 2U);
  EXPECT_LT(html.find("columns-2"), html.find("<p>left</p>"));
  EXPECT_LT(html.find("<p>left</p>"), html.find("<p>right</p>"));
  EXPECT_EQ(report.sections()[1].columns(), 1);

  Section section("Bad");
  EXPECT_THROW(section.setColumns(0), std::invalid_argument);
  EXPECT_THROW(section.setColumns(5), std::invalid_argument);
  try {
    section.setColumns(7);
  } catch (const std::invalid_argument& error) {
    EXPECT_NE(std::string(error.what()).find("section \"Bad\""), std::string::npos) << error.what();
    EXPECT_NE(std::string(error.what()).find("1 .. 4"), std::string::npos) << error.what();
  }
  EXPECT_EQ(section.columns(), 1);
}

}  // namespace
}  // namespace fullarm::reports
