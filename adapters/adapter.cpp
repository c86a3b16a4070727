// The adapter registry and the read-back measures every engine shares.
#include "adapter.h"

#include <bit>
#include <cstring>

#include "adapter_factories.h"
#include "quadrant/bit_hash.h"
#include "quadrant/error.h"

namespace quadrant::scene {

std::vector<std::string> AdapterNames() { return {"quadrant", "box2d", "bullet", "chipmunk"}; }

std::unique_ptr<Adapter> MakeAdapter(std::string_view name) {
  if (name == "quadrant") return MakeQuadrantAdapter("");
  if (name.starts_with("quadrant:")) return MakeQuadrantAdapter(name.substr(9));
  if (name == "box2d") return MakeBox2dAdapter();
  if (name == "bullet") return MakeBulletAdapter();
  if (name == "chipmunk") return MakeChipmunkAdapter();
  throw Error("unknown engine '" + std::string(name) +
              "' (known: quadrant, quadrant:<variant>, box2d, bullet, chipmunk)");
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
