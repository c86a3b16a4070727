// What every contact solver's preparation copies from a contact before its points: the row's ends
// (bodies, normal, friction, inverse masses, point count) and the separation its points lose to
// the polygon skin. One copy, shared by pgs's and soft_step's constraints (contact_constraints.h),
// the Jacobi solver's rows (jacobi_solve.h) and soft_step's lean rows (soft_step_rows.cpp).
#pragma once

#include "dynamics/restitution_policy.h"
#include "world/world_internal.h"

namespace quadrant {

/// The separation the points of a contact between bodies a and b lose to WorldDef::polygonSkin.
/// Shapes are read only with a skin: the quadrants scheme's private body copies carry none.
inline Real ContactSkin(const WorldDef& def, const Bodies& bodies, int a, int b) {
  return def.polygonSkin > 0 ? PolygonSkin(def, bodies.shape[a].type == ShapeType::kPolygon,
                                           bodies.shape[b].type == ShapeType::kPolygon)
                             : Real(0);
}

/// A row's ends from its contact: bodies a and b, normal, friction, inverse masses (the
/// inertias only with rotation, else 0) and point count. Returns the contact's skin
/// (ContactSkin). Row is any type with those members.
template <class Row>
[[gnu::always_inline]] inline Real CopyContactEnds(const Contact& contact, const Bodies& bodies, const WorldDef& def,
                                                   bool rotation, Row& r) {
  r.a = contact.a;
  r.b = contact.b;
  r.normal = contact.manifold.normal;
  r.friction = contact.friction;
  r.invMassA = bodies.inv[r.a].invMass;
  r.invMassB = bodies.inv[r.b].invMass;
  r.invIA = rotation ? bodies.inv[r.a].invInertia : Real(0);
  r.invIB = rotation ? bodies.inv[r.b].invInertia : Real(0);
  r.pointCount = contact.manifold.pointCount;
  return ContactSkin(def, bodies, r.a, r.b);
}

}  // namespace quadrant
