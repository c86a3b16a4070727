// Validation against Box2D 2.4.1: every canonical case (benchmarks/scenes/validation_cases.cpp,
// the same code tools/quadrant validate runs) must pass, quantity by quantity; plus the contact
// read-back the cases use.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "adapter.h"
#include "quadrant/error.h"
#include "validation_cases.h"

namespace quadrant::scene {
namespace {

class Validation : public ::testing::TestWithParam<std::string> {};

TEST_P(Validation, AgreesWithBox2dAndPhysics) {
  const ValidationResult r = RunValidationCase(GetParam());
  ASSERT_FALSE(r.quantities.empty());
  for (const ValidationQuantity& q : r.quantities) {
    EXPECT_TRUE(q.pass) << r.name << " / " << q.name << ": quadrant " << q.quadrant << ", box2d " << q.box2d
                        << ", analytic " << (q.analytic ? std::to_string(*q.analytic) : "-") << ", tolerance "
                        << q.tolerance << " (" << q.reason << ")";
  }
  EXPECT_TRUE(r.pass) << r.description;
}

std::string TestName(const ::testing::TestParamInfo<std::string>& info) {
  std::string name = info.param;
  for (char& c : name) {
    if (c == '.') c = '_';
  }
  return name;
}

INSTANTIATE_TEST_SUITE_P(Cases, Validation, ::testing::ValuesIn(ValidationCaseNames()), TestName);

TEST(ValidationCases, AtLeastFifteenAndUnknownNamesRefused) {
  EXPECT_GE(ValidationCaseNames().size(), 15u);
  EXPECT_THROW(RunValidationCase("no_such_case"), Error);
}

// The contact read-back of both engines on a box resting on a static box: scene indices, a unit
// normal from A to B, two points, impulses that carry the weight.
TEST(ContactReadback, QuadrantAndBox2dReportTheRestingManifold) {
  Scene s;
  s.name = "contact_readback";
  BodyDesc ground;
  ground.dynamic = false;
  ground.shape = ShapeKind::kPolygon;
  ground.vertices = {{-5, Real(-0.5)}, {5, Real(-0.5)}, {5, Real(0.5)}, {-5, Real(0.5)}};
  ground.position = {0, Real(-0.5)};
  ground.density = 0;
  BodyDesc box = ground;
  box.dynamic = true;
  box.density = 1;
  box.vertices = {{Real(-0.5), Real(-0.5)}, {Real(0.5), Real(-0.5)}, {Real(0.5), Real(0.5)}, {Real(-0.5), Real(0.5)}};
  box.position = {0, Real(0.5)};
  s.bodies = {ground, box};
  s.effects.restitution = false;
  // pgs and Box2D 2.4.1 report the step's impulse; the default engine (soft_step) its last
  // sub-step's, a quarter of it at 4 sub-steps.
  for (const char* engine : {"quadrant:pgs", "box2d", "quadrant"}) {
    const double perStep = std::string(engine) == "quadrant" ? 4.0 : 1.0;
    auto a = MakeAdapter(engine);
    a->Load(s, 1);
    for (int i = 0; i < 60; ++i) a->Step();
    const std::vector<ContactReadback> contacts = a->Contacts();
    ASSERT_EQ(contacts.size(), 1u) << engine;
    const ContactReadback& c = contacts[0];
    EXPECT_TRUE((c.bodyA == 0 && c.bodyB == 1) || (c.bodyA == 1 && c.bodyB == 0)) << engine;
    const double up = c.bodyA == 0 ? 1 : -1;  // normal points from A to B
    EXPECT_NEAR(c.normal.x, 0, 1e-5) << engine;
    EXPECT_NEAR(c.normal.y, up, 1e-5) << engine;
    ASSERT_EQ(c.pointCount, 2) << engine;
    EXPECT_NEAR(c.normalImpulses[0] + c.normalImpulses[1], 10.0 / 60.0 / perStep, 1e-4) << engine;
  }
  // Engines without a contact read-back return none rather than failing.
  auto bullet = MakeAdapter("bullet");
  bullet->Load(s, 1);
  bullet->Step();
  EXPECT_TRUE(bullet->Contacts().empty());
}

}  // namespace
}  // namespace quadrant::scene
