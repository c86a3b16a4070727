// The adapter registry and the read-back measures every engine shares.
#include "adapter.h"

#include <bit>
#include <cstring>

#include "adapter_factories.h"
#include "quadrant/bit_hash.h"
#include "quadrant/error.h"

namespace quadrant::scene {

// Each peer's adapter is compiled only where its library was found at configure time
// (QUADRANT_HAVE_<PEER>, adapters/CMakeLists.txt).
#ifndef QUADRANT_HAVE_BOX2D
#define QUADRANT_HAVE_BOX2D 0
#endif
#ifndef QUADRANT_HAVE_BULLET
#define QUADRANT_HAVE_BULLET 0
#endif
#ifndef QUADRANT_HAVE_CHIPMUNK
#define QUADRANT_HAVE_CHIPMUNK 0
#endif

std::vector<std::string> AdapterNames() {
  std::vector<std::string> names = {"quadrant"};
  if (QUADRANT_HAVE_BOX2D) names.push_back("box2d");
  if (QUADRANT_HAVE_BULLET) names.push_back("bullet");
  if (QUADRANT_HAVE_CHIPMUNK) names.push_back("chipmunk");
  return names;
}

#if !QUADRANT_HAVE_BOX2D || !QUADRANT_HAVE_BULLET || !QUADRANT_HAVE_CHIPMUNK
namespace {
[[noreturn]] void NotBuilt(std::string_view name, std::string_view package) {
  throw Error(std::string(name) + ": this build has no " + std::string(name) + " adapter (" + std::string(package) +
              " was not found, or switched off, when it was configured)");
}
}  // namespace
#endif

std::unique_ptr<Adapter> MakeAdapter(std::string_view name) {
  if (name == "quadrant") return MakeQuadrantAdapter("");
  if (name.starts_with("quadrant:")) return MakeQuadrantAdapter(name.substr(9));
  if (name == "box2d") {
#if QUADRANT_HAVE_BOX2D
    return MakeBox2dAdapter();
#else
    NotBuilt(name, "libbox2d-dev");
#endif
  }
  if (name == "bullet") {
#if QUADRANT_HAVE_BULLET
    return MakeBulletAdapter();
#else
    NotBuilt(name, "libbullet-dev");
#endif
  }
  if (name == "chipmunk") {
#if QUADRANT_HAVE_CHIPMUNK
    return MakeChipmunkAdapter();
#else
    NotBuilt(name, "libchipmunk-dev");
#endif
  }
  throw Error("unknown engine '" + std::string(name) +
              "' (known: quadrant, quadrant:<variant>, box2d, bullet, chipmunk)");
}

void Adapter::Load(const Scene& scene, int threads) {
  ValidateScene(scene);
  for (const BodyGroup& g : scene.groupSamples) ValidateGroup(scene, g);
  // Fewer than one thread is bad input (an Error); more than the engine runs is a limit of the
  // engine (Unsupported), which the suite reports and skips.
  if (threads < 1) throw Error(Name() + ": threads must be >= 1, got " + std::to_string(threads));
  const Capabilities caps = Caps();
  if (threads > caps.maxThreads) {
    throw Unsupported(Name() + " runs at most " + std::to_string(caps.maxThreads) + " thread(s), asked for " +
                      std::to_string(threads) + (caps.threadLimit.empty() ? "" : ": " + caps.threadLimit));
  }
  for (const BodyGroup& g : scene.groupSamples) CheckGroup(scene, g);
  DoLoad(scene, threads);  // throws before replacing the world: the old one stays loaded
  loaded_ = true;
  driver_ = scene.driver;
  step_ = 0;
  settings_ = scene;
  settings_.bodies.clear();
  settings_.joints.clear();
  settings_.groupSamples.clear();
  settings_.driver = nullptr;
  nextGroup_ = 0;
  groupLive_.clear();
}

int Adapter::AddGroup(const BodyGroup& group) {
  if (!loaded_) throw Error(Name() + ": AddGroup before Load");
  try {
    ValidateGroup(settings_, group);
  } catch (const Error& e) {
    throw Error(Name() + ": AddGroup: " + e.what());
  }
  CheckGroup(settings_, group);
  DoAddGroup(nextGroup_, group);
  groupLive_.push_back(true);
  return nextGroup_++;
}

void Adapter::RemoveGroup(int group) {
  if (!loaded_ || group < 0 || group >= nextGroup_ || !groupLive_[size_t(group)]) {
    throw Error(Name() + ": RemoveGroup: " + std::to_string(group) + " is not a group in the world (" +
                (group >= 0 && group < nextGroup_ ? "removed already" : "never added since the last Load") + ")");
  }
  DoRemoveGroup(group);
  groupLive_[size_t(group)] = false;
}

void Adapter::Step() {
  if (!loaded_) throw Error(Name() + ": Step before Load");
  if (driver_) driver_(step_, *this);
  DoStep();
  ++step_;
}

void Adapter::SetVelocity(int body, Vec2 velocity, Real angularVelocity) {
  if (!loaded_ || body < 0 || body >= BodyCount()) {
    throw Error(Name() + ": SetVelocity: body index " + std::to_string(body) + " is outside [0, " +
                std::to_string(loaded_ ? BodyCount() : 0) + ")");
  }
  // Both checked before either is set, so a refused call changes nothing.
  if (!IsFinite(velocity) || !IsFinite(angularVelocity)) {
    throw Error(Name() + ": SetVelocity: velocity is not finite");
  }
  DoSetVelocity(body, velocity, angularVelocity);
}

uint64_t Adapter::StateHash() const {
  std::vector<BodyState> states;
  ReadBodies(states);
  return HashStates(states);
}

double KineticEnergy(const Scene& scene, const std::vector<BodyState>& states) {
  double energy = 0;
  for (size_t i = 0; i < states.size() && i < scene.bodies.size(); ++i) {
    if (!scene.bodies[i].dynamic) continue;
    MassProperties mp = ComputeMassProperties(scene.bodies[i]);
    const BodyState& s = states[i];
    energy += 0.5 * mp.mass * (double(s.velocity.x) * s.velocity.x + double(s.velocity.y) * s.velocity.y);
    energy += 0.5 * mp.inertia * double(s.angularVelocity) * s.angularVelocity;
  }
  return energy;
}

Vec2 LinearMomentum(const Scene& scene, const std::vector<BodyState>& states) {
  double px = 0, py = 0;
  for (size_t i = 0; i < states.size() && i < scene.bodies.size(); ++i) {
    if (!scene.bodies[i].dynamic) continue;
    Real m = ComputeMassProperties(scene.bodies[i]).mass;
    px += double(m) * states[i].velocity.x;
    py += double(m) * states[i].velocity.y;
  }
  return {Real(px), Real(py)};
}

uint64_t HashStates(const std::vector<BodyState>& states) {
  // Equal hashes mean bit-identical read-backs.
  BitHash h;
  auto mix = [&h](Real x) { h.Mix(x); };
  for (const BodyState& s : states) {
    mix(s.position.x);
    mix(s.position.y);
    mix(s.angle);
    mix(s.velocity.x);
    mix(s.velocity.y);
    mix(s.angularVelocity);
  }
  return h.Value();
}

}  // namespace quadrant::scene
