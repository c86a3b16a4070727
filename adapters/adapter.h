// The adapter interface: one per engine, all driven through the same scene description.
#pragma once

#include <cstdint>
#include <memory>
#include <stdexcept>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "scene.h"

namespace quadrant::scene {

/// Thrown by Adapter::Load when a scene needs what the engine cannot do (an effect it cannot
/// honour or switch off, more threads than it runs). The suite reports it; it never runs the
/// scene differently in silence.
class Unsupported : public std::runtime_error {
 public:
  explicit Unsupported(const std::string& what) : std::runtime_error(what) {}
};

struct Capabilities {
  int maxThreads = 1;          ///< threads the engine really uses
  bool sleep = false;
  bool continuous = false;
  bool disableRotation = false;  ///< can run with rotation off
  bool disableFriction = true;
  bool disableWarmStarting = false;
  bool damping = false;
  std::string notes;           ///< mixing rules, settings, limitations: printed with results
  std::string threadLimit;     ///< why maxThreads is what it is (in the Unsupported message)
};

/// Per-body state as read back, in scene body order.
struct BodyState {
  Vec2 position;
  Real angle = 0;
  Vec2 velocity;
  Real angularVelocity = 0;
};

/// One touching or speculative contact manifold as an engine reports it, for validation. Body
/// indices are scene indices; the normal points from bodyA to bodyB; points and separations are
/// the engine's own (Box2D: midway between the surfaces including its 0.01 m polygon skin).
/// Impulses are those of the last step (N s).
struct ContactReadback {
  int bodyA = -1;
  int bodyB = -1;
  Vec2 normal;
  int pointCount = 0;
  Vec2 points[2];
  Real separations[2] = {0, 0};
  Real normalImpulses[2] = {0, 0};
  Real tangentImpulses[2] = {0, 0};
};

/// The interface, and the protocol every engine shares, written once here: Load validates the
/// scene and the thread count before the engine sees them, Step refuses to run before a Load and
/// runs the scene's driver, SetVelocity checks the index and the values. Each engine implements
/// DoLoad, DoStep and DoSetVelocity, which see only valid input.
class Adapter {
 public:
  virtual ~Adapter() = default;
  virtual std::string Name() const = 0;
  virtual Capabilities Caps() const = 0;
  /// Builds the engine's world for `scene` with `threads` threads. Throws quadrant::Error for an
  /// invalid scene (ValidateScene) or fewer than 1 thread, Unsupported for more threads than
  /// Caps().maxThreads or anything else the engine cannot run as described. A Load that throws
  /// keeps the previous world.
  void Load(const Scene& scene, int threads);
  /// Exactly one fixed step of scene.timeStep, after the scene's driver (if any). Throws
  /// quadrant::Error before the first Load.
  void Step();
  virtual int BodyCount() const = 0;
  /// Fills `out` with one entry per scene body, in scene order.
  virtual void ReadBodies(std::vector<BodyState>& out) const = 0;
  /// Touching contacts (manifolds with at least one point) after the last step.
  virtual int ContactCount() const = 0;
  /// Adds a group of bodies and joints to the loaded world (a scene driver's call: rain's
  /// ragdolls) and returns its id: 0, 1, 2, ... in the order of the calls since Load, never
  /// reused. Throws quadrant::Error, changing nothing, before a Load or for a group
  /// ValidateGroup refuses; Unsupported for one the engine cannot run (Load refuses a scene
  /// whose groupSamples it cannot run, so a scene's own groups never get there).
  ///
  /// Body indices (ReadBodies, SetVelocity, BodyCount): the scene's bodies first, in scene
  /// order, then the bodies of the groups still in the world by ascending group id, each group's
  /// in its own order. Removing a group moves the bodies of later groups down by its size.
  int AddGroup(const BodyGroup& group);
  /// Removes a group's bodies, and their joints with them. Throws quadrant::Error, changing
  /// nothing, for an id that AddGroup has not returned since the last Load or that was removed.
  void RemoveGroup(int group);
  /// Sets a body's velocity (for drivers and validation cases). Throws quadrant::Error, changing
  /// nothing, for an index outside [0, BodyCount()) or a non-finite value.
  void SetVelocity(int body, Vec2 velocity, Real angularVelocity);
  /// 64-bit hash of the state; Quadrant returns World::StateHash, others hash ReadBodies.
  virtual uint64_t StateHash() const;
  /// Milliseconds per pipeline stage summed over the steps since Load, for engines that time
  /// their stages (Quadrant: broad_phase, narrow_phase, persistence, solve, integrate, total).
  /// Empty for engines that do not.
  virtual std::vector<std::pair<std::string, double>> StageTotals() const { return {}; }
  /// Contact manifolds after the last step, for engines that can report them (Quadrant, Box2D);
  /// empty for the others. Not for timed loops: it builds the list on every call.
  virtual std::vector<ContactReadback> Contacts() const { return {}; }

 protected:
  /// The engine's own part of Load: the scene is valid and threads in [1, Caps().maxThreads].
  /// Throws Unsupported for what the engine cannot honour, before replacing its world.
  virtual void DoLoad(const Scene& scene, int threads) = 0;
  /// One step of the loaded world (the driver has run).
  virtual void DoStep() = 0;
  /// The body index is valid and the values finite.
  virtual void DoSetVelocity(int body, Vec2 velocity, Real angularVelocity) = 0;
  /// Throws Unsupported for a group (valid, ValidateGroup) that the engine cannot run, with the
  /// reason; Load calls it on every groupSample before DoLoad, AddGroup before DoAddGroup.
  virtual void CheckGroup(const Scene& scene, const BodyGroup& group) const = 0;
  /// Adds a valid, supported group under the id `group` (the next one); its bodies come after
  /// every live group's. Nothing changes if it throws.
  virtual void DoAddGroup(int group, const BodyGroup& group_desc) = 0;
  /// Removes the live group `group`.
  virtual void DoRemoveGroup(int group) = 0;

 private:
  bool loaded_ = false;
  Scene settings_;  ///< the loaded scene's settings (no bodies), for ValidateGroup and CheckGroup
  int nextGroup_ = 0;
  std::vector<bool> groupLive_;  ///< by group id since Load
  Driver driver_;
  int step_ = 0;  ///< steps since Load: the driver's step index
};

/// Engine names: "quadrant", "box2d", "bullet", "chipmunk" (and solver/scheme variants of
/// quadrant written "quadrant:<variant>"). Throws quadrant::Error for an unknown name.
std::unique_ptr<Adapter> MakeAdapter(std::string_view name);
std::vector<std::string> AdapterNames();

// Read-back measures shared by every engine (computed from ReadBodies and the scene's masses).
double KineticEnergy(const Scene& scene, const std::vector<BodyState>& states);
Vec2 LinearMomentum(const Scene& scene, const std::vector<BodyState>& states);
uint64_t HashStates(const std::vector<BodyState>& states);

}  // namespace quadrant::scene
