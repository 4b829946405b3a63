// Contacts of a Fetch state, as MuJoCo holds them after a step (d->contact after mj_step: the
// last substep's collision) with their normal forces (mj_contactForce), sorted into the pairs that
// matter in the object tasks: finger-object, object-table, finger-table, other. Reading them
// never changes the simulation (record --signals contacts, --overlay contacts, probe-actions).
#pragma once

#include <mujoco/mujoco.h>

#include <array>
#include <string>
#include <vector>

namespace fetchscope {

/// Which pair a contact is, from the bodies of its two geoms.
enum class ContactPair {
  kFingerObject,  ///< a gripper finger and the object
  kObjectTable,   ///< the object and the table
  kFingerTable,   ///< a gripper finger and the table
  kOther,         ///< anything else (the robot's links, the floor...)
};

/// "finger-object", "object-table", "finger-table", "other".
const char* ContactPairName(ContactPair pair);

/// The bodies that name the pairs in one model (-1 where the model lacks one).
struct ContactBodies {
  int left_finger = -1;   ///< robot0:l_gripper_finger_link
  int right_finger = -1;  ///< robot0:r_gripper_finger_link
  int object = -1;        ///< object0
  int table = -1;         ///< table0
};

/// Finds them by name in `model`.
ContactBodies FindContactBodies(const mjModel* model);

/// One active contact (included in the constraint solver: efc_address >= 0).
struct Contact {
  int index = 0;             ///< in d->contact
  std::string geom1, geom2;  ///< the model's geom names ("geom N" where unnamed)
  std::string body1, body2;  ///< their bodies' names
  ContactPair pair = ContactPair::kOther;
  std::array<double, 3> position{};  ///< m, world: midway between the geoms
  std::array<double, 3> normal{};    ///< unit, world: from geom1 towards geom2 (frame[0:3])
  double normal_force = 0;           ///< N, mj_contactForce's normal component (>= 0: pushing)
  double penetration = 0;            ///< m: max(0, -dist)
  double distance = 0;               ///< m: MuJoCo's dist (negative: overlapping)
  /// Unit direction of the force the pair's second party receives: into the object from a finger
  /// or the table, into a finger from the table; geom1 to geom2 for other pairs.
  std::array<double, 3> push{};
};

/// What a step's contacts say of the grasp.
struct ContactSignals {
  double left_finger_force = 0;   ///< N: the left finger's normal force on the object (summed)
  double right_finger_force = 0;  ///< N: the right finger's
  bool object_on_table = false;   ///< the object touches the table
  std::vector<Contact> contacts;  ///< every active contact, in d->contact's order

  /// Both fingers press the object.
  bool grasped() const { return left_finger_force > 0 && right_finger_force > 0; }
};

/// The active contacts of `d` and what they say (nothing of the object on Reach).
ContactSignals ReadContacts(const mjModel* m, const mjData* d, const ContactBodies& bodies);

}  // namespace fetchscope
