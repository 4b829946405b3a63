// What each index of a Fetch observation is: the labels `describe` prints (grip_pos.x,
// object_pos.x, object_rot.z, ...), their meaning and unit. Also names the values of a replay's
// divergence (record --from DATASET).
#pragma once

#include <vector>

namespace fetchscope {

/// One observation index as describe labels it.
struct ObservationLabel {
  const char* name;     ///< e.g. "grip_pos.x": slice name, '.', component
  const char* meaning;  ///< one line
  const char* unit;     ///< "m", "m/step", "rad", ...
};

/// The label of every observation index, in order (10 for Reach, 25 for the object tasks).
std::vector<ObservationLabel> ObservationLabels(bool has_object);

/// The label of observation[index], or nullptr outside the observation.
const ObservationLabel* FindObservationLabel(bool has_object, int index);

}  // namespace fetchscope
