#include "src/exec_wire.h"

#include <algorithm>
#include <optional>

#include "base/errors.h"
#include "base/json_util.h"
#include "base/suggest.h"
#include "src/observation_layout.h"

namespace fetchscope {
namespace {

constexpr const char* kGymnasiumKeys[] = {"observation", "achieved_goal", "desired_goal"};

std::string Joined(const std::vector<std::string>& names) {
  std::string s;
  for (const std::string& n : names) s += (s.empty() ? "" : ", ") + n;
  return s;
}

nlohmann::json CameraJson(const WireCamera& c) {
  return {{"name", c.name},
          {"fovy", JsonDouble(c.fovy)},
          {"fx", JsonDouble(c.fx)},
          {"fy", JsonDouble(c.fy)},
          {"cx", JsonDouble(c.cx)},
          {"cy", JsonDouble(c.cy)},
          {"pose", JsonVector(c.pose.data(), c.pose.size())}};
}

}  // namespace

std::vector<std::string> ExecFieldNames(bool has_object) {
  std::vector<std::string> names(std::begin(kGymnasiumKeys), std::end(kGymnasiumKeys));
  for (const ObservationSlice& slice : ObservationSlices(has_object)) names.push_back(slice.name);
  return names;
}

std::vector<std::string> ParseExecFields(const std::string& text, bool has_object) {
  if (text.empty() || text == "all") return {};
  const std::vector<std::string> accepted = ExecFieldNames(has_object);
  std::vector<std::string> fields;
  size_t start = 0;
  while (true) {
    const size_t comma = text.find(',', start);
    const std::string name = text.substr(start, comma == std::string::npos ? comma : comma - start);
    if (std::find(accepted.begin(), accepted.end(), name) == accepted.end()) {
      const std::vector<std::string> other = ExecFieldNames(!has_object);
      const bool other_task = std::find(other.begin(), other.end(), name) != other.end();
      throw UsageError("--exec-fields: unknown field '" + name + "'" +
                       (other_task ? " (this task has no object)" : DidYouMean(name, accepted)) +
                       "; accepted: all, or a comma-separated list of " + Joined(accepted));
    }
    if (std::find(fields.begin(), fields.end(), name) != fields.end()) {
      throw UsageError("--exec-fields: '" + name + "' is given twice");
    }
    fields.push_back(name);
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  return fields;
}

nlohmann::json ExecMessage(const Observation& obs, int t, const std::vector<std::string>& fields,
                           const WireStep* step, bool with_legend) {
  nlohmann::json msg;
  msg["t"] = t;
  auto add = [&](const std::string& name) {
    if (name == "observation") {
      msg[name] = JsonVector(obs.observation.data(), obs.observation.size());
    } else if (name == "achieved_goal") {
      msg[name] = JsonVector(obs.achieved_goal.data(), 3);
    } else if (name == "desired_goal") {
      msg[name] = JsonVector(obs.desired_goal.data(), 3);
    } else {
      const std::optional<bool> has_object = LayoutHasObject(obs.observation.size());
      const std::optional<ObservationSlice> slice =
          has_object ? FindObservationSlice(*has_object, name) : std::nullopt;
      if (!slice) throw RunError("exec policy: the observation has no field '" + name + "'");
      msg[name] = JsonVector(obs.observation.data() + slice->first, slice->end - slice->first);
    }
  };
  if (fields.empty()) {
    for (const char* name : kGymnasiumKeys) add(name);
  } else {
    for (const std::string& name : fields) add(name);
  }
  if (!step) return msg;
  nlohmann::json cameras = nlohmann::json::array();
  for (const WireCamera& c : step->cameras) cameras.push_back(CameraJson(c));
  nlohmann::json images = nlohmann::json::array();
  for (const WireImage& im : step->images) {
    images.push_back({{"name", im.name},
                      {"layer", im.layer},
                      {"shape", im.shape},
                      {"dtype", im.dtype},
                      {"bytes", im.bytes}});
  }
  msg["cameras"] = std::move(cameras);
  msg["images"] = std::move(images);
  if (with_legend && !step->legend.is_null()) msg["segmentation_legend"] = step->legend;
  return msg;
}

}  // namespace fetchscope
