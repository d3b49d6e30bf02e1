// The map server's pure part: what it serves for a profile, that serving never writes to the
// store, and the bounded wait for a map that has not been saved yet.

#include "mapstore/map_server.h"

#include <cmath>

#include <gtest/gtest.h>

#include "common/layers.h"
#include "mapstore/in_memory_map_store.h"
#include "mapstore/map_operations.h"
#include "mapstore/sqlite_map_store.h"
#include "tests/unit/mapstore/fake_deriver.h"

namespace cairn::mapstore {
namespace {

using testing::FakeDeriver;
using testing::Profile;
using testing::SampleSnapshot;

class MapServerTest : public ::testing::Test {
 protected:
  MapServerTest() : deriver_(FakeDeriver()) {
    const WriteContext ctx{"unit", 0, 0};
    EXPECT_TRUE(store_.PutProfile(Profile("pioneer3at", 8.0, 0.03), ctx).ok());
    EXPECT_TRUE(store_.PutProfile(Profile("rover", 12.0, 0.08), ctx).ok());
  }
  MapInfo Save(const std::string& name) {
    auto info = store_.SaveMap(SampleSnapshot(name), {"unit", 0, 0});
    EXPECT_TRUE(info.ok()) << info.status().ToString();
    return info.ok() ? *info : MapInfo{};
  }
  static const common::Obstacle* Find(const common::ObstacleRegistry& r, int id) {
    for (const auto& o : r.obstacles) {
      if (o.id == id) return &o;
    }
    return nullptr;
  }

  InMemoryMapStore store_;
  ProfileDeriver deriver_;
};

TEST(MapServerNamesTest, ServesElevationAndTheProfilesCostLayerUnderTheStoredName) {
  EXPECT_EQ(ServedLayers("rover"),
            (std::vector<std::string>{"elevation", "sonar/occupancy", "directed/rover",
                                      "cost/rover"}));
  EXPECT_EQ(ServedMapName({"tunnel", "lanes", 3}), "tunnel/lanes");
  EXPECT_TRUE(ServedAsOccupancy("sonar/occupancy"));
  EXPECT_FALSE(ServedAsOccupancy("cost/rover"));
  EXPECT_FALSE(ServedAsOccupancy("elevation"));
}

TEST(MapServerParamsTest, ValidateNamesTheBadField) {
  MapServerParams p;
  p.db_path = "site.db";
  p.ref = {"tunnel", "lanes", 0};
  p.profile = "rover";
  p.robot = "rover";
  EXPECT_NO_THROW(p.Validate());
  auto expect_throw = [](MapServerParams bad, const std::string& text) {
    try {
      bad.Validate();
      ADD_FAILURE() << "no throw, expected '" << text << "'";
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(text), std::string::npos) << e.what();
    }
  };
  MapServerParams bad = p;
  bad.db_path = "";
  expect_throw(bad, "database");
  bad = p;
  bad.ref.name = "";
  expect_throw(bad, "map name");
  bad = p;
  bad.profile = "../x";
  expect_throw(bad, "profile");
  bad = p;
  bad.robot = "";
  expect_throw(bad, "robot");
  bad = p;
  bad.wait_s = -1;
  expect_throw(bad, "wait_s");
  bad = p;
  bad.announce_period_s = 0;
  expect_throw(bad, "periods");
  bad = p;
  bad.ref.version = -2;
  expect_throw(bad, "version");
}

TEST_F(MapServerTest, LoadsElevationCostAndTheProfilesVerdicts) {
  const MapInfo saved = Save("lanes");
  auto rover = LoadServedMap(store_, &deriver_, {"lab", "lanes", 0}, "rover");
  ASSERT_TRUE(rover.ok()) << rover.status().ToString();
  EXPECT_EQ(rover->info.version, saved.version);
  EXPECT_EQ(rover->profile, "rover");
  EXPECT_EQ(rover->layers.layer_names(),
            (std::vector<std::string>{"cost/rover", "directed/rover", "elevation"}));
  EXPECT_EQ(rover->layers.geometry(), saved.geometry);
  EXPECT_FALSE(rover->from_cache);
  EXPECT_EQ(rover->obstacles.map_version, saved.version);

  // The stored elevation as saved; the fake derivation: 5 cm per cell is a step for pioneer3at
  // (3 cm), not for the rover (8 cm).
  const common::Layer& e = rover->layers.at("elevation");
  EXPECT_TRUE(std::isnan(e(0, 0)));
  EXPECT_FLOAT_EQ(e(20, 5), 0.05f * 10 + 0.005f);
  EXPECT_EQ(rover->layers.at("cost/rover")(20, 5), 0.f);
  auto pioneer = LoadServedMap(store_, &deriver_, {"lab", "lanes", 0}, "pioneer3at");
  ASSERT_TRUE(pioneer.ok()) << pioneer.status().ToString();
  EXPECT_EQ(pioneer->layers.at("cost/pioneer3at")(20, 5), 100.f);
  EXPECT_FALSE(pioneer->layers.HasLayer("cost/rover"));

  // The 10 degree ramp (id 7): crossable for the rover only, each registry with its own verdict.
  const common::Obstacle* ramp = Find(rover->obstacles, 7);
  ASSERT_NE(ramp, nullptr);
  ASSERT_EQ(ramp->verdicts.size(), 1u);
  EXPECT_EQ(ramp->verdicts[0].profile, "rover");
  EXPECT_TRUE(ramp->verdicts[0].crossable);
  ramp = Find(pioneer->obstacles, 7);
  ASSERT_NE(ramp, nullptr);
  ASSERT_EQ(ramp->verdicts.size(), 1u);
  EXPECT_FALSE(ramp->verdicts[0].crossable);
}

TEST_F(MapServerTest, UsesTheDerivedCacheWhenTheMapWasShared) {
  Save("lanes");
  auto shared = ShareMap(store_, deriver_, {"lab", "lanes", 0}, "rover", {"unit", 0, 0});
  ASSERT_TRUE(shared.ok()) << shared.status().ToString();
  auto served = LoadServedMap(store_, &deriver_, {"lab", "lanes", 0}, "rover");
  ASSERT_TRUE(served.ok()) << served.status().ToString();
  EXPECT_TRUE(served->from_cache);
  EXPECT_EQ(served->derive_ms, 0.0);
  // The cache is keyed by the derivation's code version: without a deriver nothing is served.
  const auto no_deriver = LoadServedMap(store_, nullptr, {"lab", "lanes", 0}, "rover");
  EXPECT_EQ(no_deriver.status().code(), common::StatusCode::kUnavailable);
  // A derivation of another code version does not use the cache.
  const ProfileDeriver newer = FakeDeriver("fake-2");
  auto fresh = LoadServedMap(store_, &newer, {"lab", "lanes", 0}, "rover");
  ASSERT_TRUE(fresh.ok()) << fresh.status().ToString();
  EXPECT_FALSE(fresh->from_cache);
}

TEST_F(MapServerTest, ServingNeverWritesToTheStore) {
  const MapInfo saved = Save("lanes");
  const auto audit_before = store_.ListAudit(100);
  ASSERT_TRUE(audit_before.ok());
  ASSERT_TRUE(LoadServedMap(store_, &deriver_, {"lab", "lanes", 0}, "rover").ok());
  ASSERT_TRUE(LoadServedMap(store_, &deriver_, {"lab", "lanes", saved.version}, "rover").ok());
  const auto derived = store_.ListDerived({"lab", "lanes", saved.version});
  ASSERT_TRUE(derived.ok());
  EXPECT_TRUE(derived->empty()) << "the derivation was cached by a read";
  EXPECT_EQ(store_.ListAudit(100)->size(), audit_before->size());
}

TEST_F(MapServerTest, ServingNeverWritesTheSqliteFile) {
  const std::string path = ::testing::TempDir() + "/map_server_test.db";
  std::remove(path.c_str());
  {
    auto writer = SqliteMapStore::Open(path);
    ASSERT_TRUE(writer.ok()) << writer.status().ToString();
    ASSERT_TRUE((*writer)->PutProfile(Profile("rover", 12.0, 0.08), {"unit", 0, 0}).ok());
    ASSERT_TRUE((*writer)->SaveMap(SampleSnapshot("lanes"), {"unit", 0, 0}).ok());
  }
  SqliteOptions read_only;
  read_only.read_only = true;
  auto reader = SqliteMapStore::Open(path, read_only);
  ASSERT_TRUE(reader.ok()) << reader.status().ToString();
  auto served = LoadServedMap(**reader, &deriver_, {"lab", "lanes", 0}, "rover");
  ASSERT_TRUE(served.ok()) << served.status().ToString();
  EXPECT_TRUE(served->layers.HasLayer("cost/rover"));
  auto derived = (*reader)->ListDerived({"lab", "lanes", served->info.version});
  ASSERT_TRUE(derived.ok());
  EXPECT_TRUE(derived->empty());
}

TEST_F(MapServerTest, MissingMapVersionOrProfileIsNotFoundAndMayAppearLater) {
  auto no_map = LoadServedMap(store_, &deriver_, {"lab", "lanes", 0}, "rover");
  EXPECT_EQ(no_map.status().code(), common::StatusCode::kNotFound);
  EXPECT_TRUE(MayAppearLater(no_map.status()));
  Save("lanes");
  auto no_version = LoadServedMap(store_, &deriver_, {"lab", "lanes", 9}, "rover");
  EXPECT_EQ(no_version.status().code(), common::StatusCode::kNotFound);
  auto no_profile = LoadServedMap(store_, &deriver_, {"lab", "lanes", 0}, "kobuki");
  EXPECT_EQ(no_profile.status().code(), common::StatusCode::kNotFound);
  EXPECT_FALSE(MayAppearLater(common::CorruptError("bad blob")));
  EXPECT_FALSE(MayAppearLater(common::InvalidArgumentError("no elevation")));
  EXPECT_TRUE(MayAppearLater(common::UnavailableError("locked")));
}

TEST_F(MapServerTest, AMapWithoutElevationServesItsCostLayerOnlyOrCannotBeDerived) {
  MapSnapshot flat = SampleSnapshot("flat");
  flat.base = common::GridMap(flat.base.geometry());
  flat.base.AddLayer(layers::kObservationCount).setConstant(1.f);
  ASSERT_TRUE(store_.SaveMap(flat, {"unit", 0, 0}).ok());
  auto served = LoadServedMap(store_, &deriver_, {"lab", "flat", 0}, "rover");
  // The fake derivation, like the real one, needs elevation.
  EXPECT_EQ(served.status().code(), common::StatusCode::kInvalidArgument);
  EXPECT_FALSE(MayAppearLater(served.status()));
}

TEST(MapWaiterTest, WaitsLogsOnceThenServes) {
  MapWaiter dut(10.0);
  const auto missing = common::NotFoundError("no map 'tunnel/lanes'");
  auto d = dut.OnAttempt(0.0, missing);
  EXPECT_EQ(d.action, MapWaiter::Action::kWait);
  ASSERT_TRUE(d.log.has_value());
  EXPECT_NE(d.log->find("waiting up to 10.0 s"), std::string::npos) << *d.log;
  EXPECT_NE(d.log->find("no map 'tunnel/lanes'"), std::string::npos) << *d.log;
  for (double t : {1.0, 2.0, 5.0}) {
    d = dut.OnAttempt(t, missing);
    EXPECT_EQ(d.action, MapWaiter::Action::kWait);
    EXPECT_FALSE(d.log.has_value()) << "logged again at " << t << " s: " << *d.log;
  }
  d = dut.OnAttempt(6.5, common::UnavailableError("locked"));
  EXPECT_EQ(d.action, MapWaiter::Action::kWait);
  EXPECT_FALSE(d.log.has_value());
  d = dut.OnAttempt(7.0, common::Status::Ok());
  EXPECT_EQ(d.action, MapWaiter::Action::kServe);
  ASSERT_TRUE(d.log.has_value());
  EXPECT_NE(d.log->find("7.0 s"), std::string::npos) << *d.log;
  EXPECT_TRUE(dut.waited());
}

TEST(MapWaiterTest, GivesUpAfterTheBoundOrAtOnceWithoutOne) {
  MapWaiter bounded(3.0);
  const auto missing = common::NotFoundError("no map");
  EXPECT_EQ(bounded.OnAttempt(0.0, missing).action, MapWaiter::Action::kWait);
  auto d = bounded.OnAttempt(3.0, missing);
  EXPECT_EQ(d.action, MapWaiter::Action::kGiveUp);
  ASSERT_TRUE(d.log.has_value());
  EXPECT_NE(d.log->find("gave up after waiting 3.0 s"), std::string::npos) << *d.log;

  MapWaiter none(0.0);
  d = none.OnAttempt(0.0, missing);
  EXPECT_EQ(d.action, MapWaiter::Action::kGiveUp);
  EXPECT_NE(d.log->find("no map to serve"), std::string::npos) << *d.log;
  EXPECT_FALSE(none.waited());

  MapWaiter served_at_once(0.0);
  d = served_at_once.OnAttempt(0.0, common::Status::Ok());
  EXPECT_EQ(d.action, MapWaiter::Action::kServe);
  EXPECT_FALSE(d.log.has_value());
}

TEST(MapWaiterTest, ANonTransientFailureEndsTheWait) {
  MapWaiter dut(100.0);
  EXPECT_EQ(dut.OnAttempt(0.0, common::NotFoundError("no map")).action, MapWaiter::Action::kWait);
  auto d = dut.OnAttempt(1.0, common::CorruptError("tile (0, 0) of elevation"));
  EXPECT_EQ(d.action, MapWaiter::Action::kGiveUp);
  EXPECT_NE(d.log->find("CORRUPT"), std::string::npos) << *d.log;
}

}  // namespace
}  // namespace cairn::mapstore
