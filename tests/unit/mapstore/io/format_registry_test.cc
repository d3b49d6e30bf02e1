#include "mapstore/io/format_registry.h"

#include <cmath>
#include <sstream>

#include <gtest/gtest.h>

#include "common/layers.h"
#include "mapstore/in_memory_map_store.h"
#include "mapstore/io/files.h"
#include "mapstore/map_transfer.h"
#include "tests/unit/mapstore/fake_deriver.h"
#include "tests/unit/mapstore/io/io_test_support.h"

namespace cairn::mapstore::io {
namespace {

using common::Result;
using common::Status;
using common::StatusCode;

// A tiny format registered through the seam, as a new format would be: "<stem>.count" holds
// the number of known cells of a layer; importing it writes that number into a layer "count".
void RegisterCountFormat(FormatRegistry* registry) {
  registry->AddExporter({"count", "known cells of a layer",
                         [](const ExportContext& ctx) -> Result<std::vector<std::string>> {
                           auto layer =
                               ctx.ChooseLayer({layers::kElevation}, /*or_first_layer=*/true);
                           if (!layer.ok()) return layer.status();
                           auto map = ctx.LoadLayer(*layer);
                           if (!map.ok()) return map.status();
                           const common::Layer& cells = map->at(*layer);
                           int64_t known = 0;
                           for (Eigen::Index i = 0; i < cells.size(); ++i)
                             known += !std::isnan(cells.data()[i]);
                           auto path = OutputPath(ctx.options().folder, ctx.Stem(*layer), ".count");
                           if (!path.ok()) return path.status();
                           const Status s =
                               WriteFileAtomically(*path, std::to_string(known) + "\n");
                           if (!s.ok()) return s;
                           return std::vector<std::string>{*path};
                         }});
  registry->AddImporter({"count",
                         {".count"},
                         "a count into layer 'count'",
                         [](const std::string& path, ImportTarget& target) -> Status {
                           Status s = target.StartFromLatest();
                           if (!s.ok()) return s;
                           auto text = ReadFile(path);
                           if (!text.ok()) return text.status();
                           target.snapshot().base.AddLayer("count", std::stof(*text));
                           return Status::Ok();
                         }});
}

class FormatRegistryTest : public ::testing::Test {
 protected:
  FormatRegistryTest() {
    EXPECT_TRUE(store_.SaveMap(mapstore::testing::SampleSnapshot("corridor"), {"unit", 0, 0}).ok());
    options_.ref = {"lab", "corridor", 0};
    options_.folder = testing::TempDir();
  }
  InMemoryMapStore store_;
  ExportOptions options_;
};

TEST_F(FormatRegistryTest, ATestFormatRegisteredThroughTheSeamExportsAndImports) {
  FormatRegistry formats;
  RegisterBuiltinFormats(&formats);
  RegisterCountFormat(&formats);
  options_.format = "count";
  auto files = ExportMap(store_, nullptr, options_, formats);
  ASSERT_TRUE(files.ok()) << files.status().ToString();
  ASSERT_EQ(files->size(), 1u);
  EXPECT_EQ(std::filesystem::path(files->front()).filename(), "corridor_v1_elevation.count");
  auto text = ReadFile(files->front());
  ASSERT_TRUE(text.ok());
  EXPECT_EQ(*text, std::to_string(37 * 23 - 4 * 3) + "\n");  // all but the unknown corner

  ImportOptions import;
  import.path = files->front();
  import.site = "lab";
  import.name = "corridor";
  auto info = ImportMap(store_, import, {"unit", 0, 0}, formats);
  ASSERT_TRUE(info.ok()) << info.status().ToString();
  EXPECT_EQ(info->version, 2);
  auto count = store_.LoadLayers({"lab", "corridor", 2}, {{"count"}, std::nullopt});
  ASSERT_TRUE(count.ok());
  EXPECT_EQ(count->at("count")(0, 0), 37.f * 23 - 12);
  // The built-in formats do not know it; the message lists those they know.
  auto unknown = ExportMap(store_, nullptr, options_);
  EXPECT_EQ(unknown.status().code(), StatusCode::kInvalidArgument);
  EXPECT_EQ(unknown.status().message(),
            "unknown export format 'count' (bt, csv, directed, ot, png, ros, ros-raw, ros-scale, "
            "ros-trinary)");
  EXPECT_EQ(ImportMap(store_, import, {"unit", 0, 0}).status().code(),
            StatusCode::kInvalidArgument);
}

TEST_F(FormatRegistryTest, TheBuiltinFormatsAreRegisteredByName) {
  const FormatRegistry& formats = BuiltinFormats();
  EXPECT_EQ(formats.ExportNames(),
            (std::vector<std::string>{"bt", "csv", "directed", "ot", "png", "ros", "ros-raw",
                                      "ros-scale", "ros-trinary"}));
  EXPECT_EQ(formats.ImportNames(), (std::vector<std::string>{"bt", "csv", "ot", "ros"}));
  for (const auto& [name, format] : formats.exporters()) EXPECT_FALSE(format.summary.empty());
  ASSERT_NE(formats.ImporterForPath("maps/Site.YML"), nullptr);
  EXPECT_EQ(formats.ImporterForPath("maps/Site.YML")->name, "ros");
  EXPECT_EQ(formats.ImporterForPath("tree.bt")->name, "bt");
  EXPECT_EQ(formats.ImporterForPath("notes.txt"), nullptr);
  ImportOptions import;
  import.path = "notes.txt";
  import.name = "corridor";
  import.site = "lab";
  auto refused = ImportMap(store_, import, {"unit", 0, 0});
  EXPECT_EQ(refused.status().code(), StatusCode::kInvalidArgument);
  EXPECT_EQ(refused.status().message(),
            "cannot import 'notes.txt': expected .bt (bt), .csv (csv), .ot (ot), .yaml/.yml (ros)");
}

TEST_F(FormatRegistryTest, ANameOrExtensionRegisteredTwiceIsABug) {
  FormatRegistry formats;
  RegisterBuiltinFormats(&formats);
  EXPECT_THROW(RegisterBuiltinFormats(&formats), std::invalid_argument);
  EXPECT_THROW(
      formats.AddImporter({"yaml2",
                           {".yaml"},
                           "again",
                           [](const std::string&, ImportTarget&) { return Status::Ok(); }}),
      std::invalid_argument);
  EXPECT_THROW(formats.AddExporter({"nothing", "no writer", nullptr}), std::invalid_argument);
  EXPECT_THROW(
      formats.AddImporter({"bad",
                           {"csv2"},
                           "no dot",
                           [](const std::string&, ImportTarget&) { return Status::Ok(); }}),
      std::invalid_argument);
}

TEST_F(FormatRegistryTest, TheExportContextChoosesLayersAndStems) {
  auto info = store_.GetMapInfo({"lab", "corridor", 0});
  ASSERT_TRUE(info.ok());
  ExportContext ctx(store_, nullptr, *info, options_);
  EXPECT_EQ(ctx.Stem(), "corridor_v1");
  EXPECT_EQ(ctx.Stem("cost/rover"), "corridor_v1_cost_rover");
  EXPECT_EQ(ctx.ChooseLayer({"static", layers::kObservationCount}, false).value(),
            layers::kObservationCount);
  EXPECT_EQ(ctx.ChooseLayer({"static"}, true).value(), info->layers.front());
  EXPECT_EQ(ctx.ChooseLayer({"static"}, false, "none here").status().message(), "none here");
  ExportOptions named = options_;
  named.stem = "mine";
  named.profile = "rover";
  ExportContext with_profile(store_, nullptr, *info, named);
  EXPECT_EQ(with_profile.Stem("anything"), "mine");
  EXPECT_EQ(with_profile.ChooseLayer({layers::kElevation}, true).value(), "cost/rover");
  EXPECT_EQ(with_profile.LoadLayer("cost/rover").status().code(), StatusCode::kNotFound);
  EXPECT_EQ(ctx.LoadLayer("../x").status().code(), StatusCode::kInvalidArgument);
}

}  // namespace
}  // namespace cairn::mapstore::io
