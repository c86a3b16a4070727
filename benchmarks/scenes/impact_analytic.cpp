// Stronge's integration over the normal impulse, exact phase by phase (impact_analytic.h).
#include "impact_analytic.h"

#include <cmath>

namespace quadrant::scene {
namespace {

// Velocity of a body's material point at r.
void PointVelocity(const ImpactBody& body, double& x, double& y) {
  x = body.vx - body.w * body.ry;
  y = body.vy + body.w * body.rx;
}

}  // namespace

double ImpactKineticEnergy(const ImpactBody& a, const ImpactBody& b) {
  double e = 0;
  for (const ImpactBody* body : {&a, &b}) {
    if (body->invMass > 0) e += 0.5 * (body->vx * body->vx + body->vy * body->vy) / body->invMass;
    if (body->invInertia > 0) e += 0.5 * body->w * body->w / body->invInertia;
  }
  return e;
}

ImpactResult SolveImpact(const ImpactInput& in) {
  ImpactResult r;
  r.a = in.a;
  r.b = in.b;
  const double nx = in.nx, ny = in.ny, tx = -ny, ty = nx;
  // The 2x2 inverse effective mass in the (n, t) frame: a unit impulse P on B (and -P on A)
  // changes the relative contact velocity by K P. With s = perp(r) = (-r.y, r.x), a body adds
  // invInertia * s s^T.
  const double m = in.a.invMass + in.b.invMass;
  const double sAn = -in.a.ry * nx + in.a.rx * ny, sAt = -in.a.ry * tx + in.a.rx * ty;
  const double sBn = -in.b.ry * nx + in.b.rx * ny, sBt = -in.b.ry * tx + in.b.rx * ty;
  const double knn = m + in.a.invInertia * sAn * sAn + in.b.invInertia * sBn * sBn;
  const double ktt = m + in.a.invInertia * sAt * sAt + in.b.invInertia * sBt * sBt;
  const double knt = in.a.invInertia * sAn * sAt + in.b.invInertia * sBn * sBt;
  double ax, ay, bx, by;
  PointVelocity(in.a, ax, ay);
  PointVelocity(in.b, bx, by);
  const double ux = bx - ax, uy = by - ay;
  double un = ux * nx + uy * ny, ut = ux * tx + uy * ty;
  if (!(un < 0) || !(knn > 0)) {
    r.why = "the bodies do not approach at the contact point";
    return r;
  }
  r.approachSpeed = -un;
  const double target = -in.restitution * un;  // Newton: u_n after = -e u_n before
  const double mu = in.friction;
  double pn = 0, pt = 0;
  // Slip smaller than this is taken as none (m/s): round-off of the phase arithmetic, far below
  // any speed the engines resolve in float.
  const double kSlipZero = 1e-12 * (1 + std::abs(un) + std::abs(ut));
  for (int phase = 0; phase < 8; ++phase) {
    r.phases = phase + 1;
    // Tangential impulse per unit normal impulse in this phase.
    double ratio = 0;
    bool sticking = false;
    if (mu > 0) {
      if (std::abs(ut) > kSlipZero) {
        ratio = ut > 0 ? -mu : mu;  // slip: friction at its bound, against the slip
      } else if (std::abs(knt) <= mu * ktt) {
        ratio = -knt / ktt;  // stick: the friction that keeps u_t at 0 is within the cone
        sticking = true;
        ut = 0;
      } else {
        ratio = knt > 0 ? -mu : mu;  // slip restarts in the direction K_tn drives it
        if (phase > 0) r.reversed = true;
        ut = 0;
      }
    }
    const double dun = knn + knt * ratio, dut = knt + ktt * ratio;
    if (!(dun > 0)) {
      r.why = "jam: the normal contact velocity does not rise with the normal impulse";
      return r;
    }
    double step = (target - un) / dun;  // normal impulse to the end of the impact
    bool slipStops = false;
    if (mu > 0 && !sticking && std::abs(ut) > kSlipZero && ut * dut < 0) {
      const double toZero = -ut / dut;
      if (toZero < step) {
        step = toZero;
        slipStops = true;
      }
    }
    pn += step;
    pt += ratio * step;
    un += dun * step;
    ut = slipStops ? 0.0 : ut + dut * step;
    if (!slipStops) {
      r.stuck = sticking;
      break;
    }
    if (phase == 7) {
      r.why = "more than 8 phases";
      return r;
    }
  }
  // Once slip has stopped the next phase sticks or reverses; a third slip phase cannot follow
  // (u_t is linear in p_n within a phase and the reversed direction is the one K_tn drives).
  const double Px = pn * nx + pt * tx, Py = pn * ny + pt * ty;
  r.a.vx -= in.a.invMass * Px;
  r.a.vy -= in.a.invMass * Py;
  r.a.w -= in.a.invInertia * (in.a.rx * Py - in.a.ry * Px);
  r.b.vx += in.b.invMass * Px;
  r.b.vy += in.b.invMass * Py;
  r.b.w += in.b.invInertia * (in.b.rx * Py - in.b.ry * Px);
  r.normalImpulse = pn;
  r.tangentImpulse = pt;
  r.finalSlip = ut;
  r.ok = true;
  return r;
}

}  // namespace quadrant::scene
