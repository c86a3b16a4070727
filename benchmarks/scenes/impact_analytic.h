// The analytic answer of a planar rigid-body impact at a single point, neither engine's: the
// reference that tells which engine's response is nearer to the mechanics (issue #17).
//
// Model: two rigid bodies meet at one point with unit normal n (from A to B); the impact is
// instantaneous, so positions do not change and only impulses act. Coulomb friction (the
// tangential impulse increment is at most mu times the normal one, opposing slip; slip stops
// when it can, sticks when |K_tn| <= mu K_tt, and reverses otherwise) and Newton's kinematic
// restitution (the normal separation speed at the end is e times the approach speed). The
// impulse is integrated over the normal impulse as Stronge does ("Impact Mechanics", 2000,
// ch. 3-5; Routh's graphical method is the same construction): the contact velocity is linear
// in the impulse, u = u0 + K P, so every phase (slip in one direction, stick) is a straight line
// in impulse space and the integration is exact, phase by phase, with no step size.
//
// Everything here is double precision and engine-neutral (no engine code is called).
#pragma once

#include <string>

namespace quadrant::scene {

struct ImpactBody {
  double invMass = 0;     ///< 1/kg (0: static)
  double invInertia = 0;  ///< 1/(kg m^2) about the centre of mass
  double vx = 0, vy = 0;  ///< centre-of-mass velocity before (m/s)
  double w = 0;           ///< angular velocity before (rad/s)
  double rx = 0, ry = 0;  ///< contact point minus centre of mass (m)
};

struct ImpactInput {
  ImpactBody a, b;
  double nx = 1, ny = 0;  ///< unit normal from A to B
  double friction = 0;    ///< Coulomb coefficient, >= 0
  double restitution = 0; ///< Newton's coefficient, 0..1
};

struct ImpactResult {
  bool ok = false;
  std::string why;          ///< when !ok: the bodies do not approach, or the impact jams
  ImpactBody a, b;          ///< velocities after (r as given)
  double normalImpulse = 0;   ///< on B (N s), >= 0
  double tangentImpulse = 0;  ///< on B along t = (-ny, nx) (N s)
  double approachSpeed = 0;   ///< -u_n before (m/s), > 0
  double finalSlip = 0;       ///< tangential contact velocity after, along t (m/s)
  bool stuck = false;         ///< slip stopped and stayed stopped
  bool reversed = false;      ///< slip stopped and restarted the other way
  int phases = 0;
};

/// Post-impact velocities of A and B. Returns ok = false (with a reason) when the normal
/// velocity is not approaching or a phase cannot progress (a jam: the normal contact velocity
/// would fall while the normal impulse grows, which no finite impulse ends).
ImpactResult SolveImpact(const ImpactInput& in);

/// Kinetic energy of the pair (J) for masses given as inverses (0 = static, no energy).
double ImpactKineticEnergy(const ImpactBody& a, const ImpactBody& b);

}  // namespace quadrant::scene
