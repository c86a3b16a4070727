// A moved-from World (issue 16): every public call throws quadrant::Error instead of following a
// null pointer and aborting the process; the World it was moved into carries the state on, and
// assigning a World to the moved-from one makes it usable again.
#include <gtest/gtest.h>

#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "quadrant/error.h"
#include "quadrant/world.h"
#include "test_helpers.h"

namespace quadrant {
namespace {

using namespace test;  // the small-world builders of test_helpers.h

constexpr const char* kMoved = "was moved from";

struct Drawer : DebugDraw {
  void DrawCircle(Vec2, Real, Real, Color) override {}
  void DrawPolygon(std::span<const Vec2>, Color) override {}
};

TEST(MovedFromWorldTest, EveryCallThrowsError) {
  World source;
  AddGround(source);
  const BodyId id = AddCircle(source, {0, 2});
  StepN(source, 5);
  const uint64_t hash = source.StateHash();
  World target(std::move(source));
  EXPECT_EQ(target.StateHash(), hash);  // the state moved with it

  BodyDef def;
  def.type = BodyType::kDynamic;
  def.shape = ShapeDef::MakeCircle(Real(0.5));
  // Every public member function but the special members, each with valid arguments.
  const std::vector<std::pair<std::string, std::function<void()>>> calls = {
      {"CreateBody", [&] { source.CreateBody(def); }},
      {"DestroyBody", [&] { source.DestroyBody(id); }},
      {"IsValid", [&] { (void)source.IsValid(id); }},
      {"Step", [&] { source.Step(kDt); }},
      {"StepRepeated", [&] { source.StepRepeated(kDt, 2); }},
      {"GetUserData", [&] { (void)source.GetUserData(id); }},
      {"SetUserData", [&] { source.SetUserData(id, 7); }},
      {"GetFilter", [&] { (void)source.GetFilter(id); }},
      {"SetFilter", [&] { source.SetFilter(id, Filter{}); }},
      {"QueryAABB", [&] { std::vector<BodyId> out; source.QueryAABB({{-1, -1}, {1, 1}}, out); }},
      {"RayCastClosest", [&] { (void)source.RayCastClosest({0, 5}, {0, -10}); }},
      {"RayCastAll", [&] { std::vector<RayHit> out; source.RayCastAll({0, 5}, {0, -10}, out); }},
      {"QueryPoint", [&] { std::vector<BodyId> out; source.QueryPoint({0, 0}, out); }},
      {"CastCircle", [&] { (void)source.CastCircle({0, 5}, 1, {0, -10}); }},
      {"CastPolygon", [&] { (void)source.CastPolygon(std::vector<Vec2>{{0, 5}, {1, 5}, {0, 6}}, {0, -10}); }},
      {"Draw", [&] { Drawer d; source.Draw(d); }},
      {"GetContactBeginEvents", [&] { (void)source.GetContactBeginEvents(); }},
      {"GetContactEndEvents", [&] { (void)source.GetContactEndEvents(); }},
      {"GetContactHitEvents", [&] { (void)source.GetContactHitEvents(); }},
      {"GetSensorBeginEvents", [&] { (void)source.GetSensorBeginEvents(); }},
      {"GetSensorEndEvents", [&] { (void)source.GetSensorEndEvents(); }},
      {"GetPosition", [&] { (void)source.GetPosition(id); }},
      {"GetAngle", [&] { (void)source.GetAngle(id); }},
      {"GetRotation", [&] { (void)source.GetRotation(id); }},
      {"GetLinearVelocity", [&] { (void)source.GetLinearVelocity(id); }},
      {"GetAngularVelocity", [&] { (void)source.GetAngularVelocity(id); }},
      {"GetWorldCenter", [&] { (void)source.GetWorldCenter(id); }},
      {"GetMass", [&] { (void)source.GetMass(id); }},
      {"GetRotationalInertia", [&] { (void)source.GetRotationalInertia(id); }},
      {"GetType", [&] { (void)source.GetType(id); }},
      {"GetAABB", [&] { (void)source.GetAABB(id); }},
      {"GetShape", [&] { (void)source.GetShape(id); }},
      {"SetLinearVelocity", [&] { source.SetLinearVelocity(id, {1, 0}); }},
      {"SetAngularVelocity", [&] { source.SetAngularVelocity(id, 1); }},
      {"SetTransform", [&] { source.SetTransform(id, {0, 3}, 0); }},
      {"ApplyLinearImpulse", [&] { source.ApplyLinearImpulse(id, {1, 0}, {0, 2}); }},
      {"ApplyAngularImpulse", [&] { source.ApplyAngularImpulse(id, 1); }},
      {"ApplyForce", [&] { source.ApplyForce(id, {1, 0}, {0, 2}); }},
      {"ApplyForceToCenter", [&] { source.ApplyForceToCenter(id, {1, 0}); }},
      {"ApplyTorque", [&] { source.ApplyTorque(id, 1); }},
      {"GetGravityScale", [&] { (void)source.GetGravityScale(id); }},
      {"SetGravityScale", [&] { source.SetGravityScale(id, 2); }},
      {"IsFixedRotation", [&] { (void)source.IsFixedRotation(id); }},
      {"SetFixedRotation", [&] { source.SetFixedRotation(id, true); }},
      {"IsBullet", [&] { (void)source.IsBullet(id); }},
      {"SetBullet", [&] { source.SetBullet(id, true); }},
      {"SetType", [&] { source.SetType(id, BodyType::kKinematic); }},
      {"SetFriction", [&] { source.SetFriction(id, 1); }},
      {"SetRestitution", [&] { source.SetRestitution(id, 1); }},
      {"SetDensity", [&] { source.SetDensity(id, 2); }},
      {"GetGravity", [&] { (void)source.GetGravity(); }},
      {"SetGravity", [&] { source.SetGravity({0, 1}); }},
      {"IsAwake", [&] { (void)source.IsAwake(id); }},
      {"SetAwake", [&] { source.SetAwake(id, true); }},
      {"GetBodyCount", [&] { (void)source.GetBodyCount(); }},
      {"GetBodyIds", [&] { (void)source.GetBodyIds(); }},
      {"GetDef", [&] { (void)source.GetDef(); }},
      {"GetProfile", [&] { (void)source.GetProfile(); }},
      {"GetCounters", [&] { (void)source.GetCounters(); }},
      {"GetContacts", [&] { (void)source.GetContacts(); }},
      {"GetOwners", [&] { (void)source.GetOwners(); }},
      {"GetPartitionRegion", [&] { (void)source.GetPartitionRegion(); }},
      {"StateHash", [&] { (void)source.StateHash(); }},
  };
  for (const auto& [name, call] : calls) ExpectError(call, kMoved, name);
  // The refusals left the moved-to world alone.
  EXPECT_EQ(target.StateHash(), hash);
  EXPECT_EQ(target.GetBodyCount(), 2);
}

TEST(MovedFromWorldTest, MoveAssignmentEmptiesTheSourceAndAssigningRevivesIt) {
  World a;
  AddCircle(a, {0, 0});
  World b;
  b = std::move(a);
  EXPECT_EQ(b.GetBodyCount(), 1);
  ExpectError([&] { (void)a.GetBodyCount(); }, kMoved, "after move assignment");
  a = World();  // usable again
  EXPECT_EQ(a.GetBodyCount(), 0);
  AddCircle(a, {0, 0});
  a.Step(kDt);
  EXPECT_EQ(a.GetBodyCount(), 1);
}

}  // namespace
}  // namespace quadrant
