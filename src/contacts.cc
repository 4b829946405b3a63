#include "src/contacts.h"

#include <algorithm>

namespace fetchscope {
namespace {

std::string Name(const mjModel* m, int type, int id) {
  const char* n = mj_id2name(m, type, id);
  return n ? n : std::string(type == mjOBJ_GEOM ? "geom " : "body ") + std::to_string(id);
}

}  // namespace

const char* ContactPairName(ContactPair pair) {
  switch (pair) {
    case ContactPair::kFingerObject:
      return "finger-object";
    case ContactPair::kObjectTable:
      return "object-table";
    case ContactPair::kFingerTable:
      return "finger-table";
    case ContactPair::kOther:
      break;
  }
  return "other";
}

ContactBodies FindContactBodies(const mjModel* model) {
  ContactBodies b;
  b.left_finger = mj_name2id(model, mjOBJ_BODY, "robot0:l_gripper_finger_link");
  b.right_finger = mj_name2id(model, mjOBJ_BODY, "robot0:r_gripper_finger_link");
  b.object = mj_name2id(model, mjOBJ_BODY, "object0");
  b.table = mj_name2id(model, mjOBJ_BODY, "table0");
  return b;
}

ContactSignals ReadContacts(const mjModel* m, const mjData* d, const ContactBodies& bodies) {
  ContactSignals s;
  const auto finger = [&](int body) {
    return body >= 0 && (body == bodies.left_finger || body == bodies.right_finger);
  };
  for (int i = 0; i < d->ncon; ++i) {
    const mjContact& con = d->contact[i];
    if (con.efc_address < 0) continue;  // not in the solver: no force
    Contact c;
    c.index = i;
    const int b1 = m->geom_bodyid[con.geom1], b2 = m->geom_bodyid[con.geom2];
    c.geom1 = Name(m, mjOBJ_GEOM, con.geom1);
    c.geom2 = Name(m, mjOBJ_GEOM, con.geom2);
    c.body1 = Name(m, mjOBJ_BODY, b1);
    c.body2 = Name(m, mjOBJ_BODY, b2);
    for (int k = 0; k < 3; ++k) {
      c.position[k] = con.pos[k];
      c.normal[k] = con.frame[k];
    }
    mjtNum force[6];
    mj_contactForce(m, d, i, force);
    c.normal_force = force[0];
    c.distance = con.dist;
    c.penetration = std::max(0.0, -con.dist);
    // the pair, and which side receives the push drawn: +normal pushes geom2 away from geom1
    int receiver = b2;
    const bool object1 = b1 == bodies.object && b1 >= 0, object2 = b2 == bodies.object && b2 >= 0;
    const bool table1 = b1 == bodies.table && b1 >= 0, table2 = b2 == bodies.table && b2 >= 0;
    if ((finger(b1) && object2) || (object1 && finger(b2))) {
      c.pair = ContactPair::kFingerObject;
      receiver = bodies.object;
      const int finger_body = finger(b1) ? b1 : b2;
      (finger_body == bodies.left_finger ? s.left_finger_force : s.right_finger_force) +=
          c.normal_force;
    } else if ((object1 && table2) || (table1 && object2)) {
      c.pair = ContactPair::kObjectTable;
      receiver = bodies.object;
      s.object_on_table = true;
    } else if ((finger(b1) && table2) || (table1 && finger(b2))) {
      c.pair = ContactPair::kFingerTable;
      receiver = finger(b1) ? b1 : b2;
    }
    const double sign = receiver == b2 ? 1.0 : -1.0;
    for (int k = 0; k < 3; ++k) c.push[k] = sign * c.normal[k];
    s.contacts.push_back(std::move(c));
  }
  return s;
}

}  // namespace fetchscope
