#include "dataset/minari_format.h"

#include <hdf5.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <regex>

#include "base/errors.h"

namespace fetchscope {
namespace {

// Gymnasium-Robotics' module and class for each task's MuJoCo (v4) env
const char* EntryPoint(Task task) {
  switch (task) {
    case Task::kReach:
      return "gymnasium_robotics.envs.fetch.reach:MujocoFetchReachEnv";
    case Task::kPush:
      return "gymnasium_robotics.envs.fetch.push:MujocoFetchPushEnv";
    case Task::kPickAndPlace:
      return "gymnasium_robotics.envs.fetch.pick_and_place:MujocoFetchPickAndPlaceEnv";
    case Task::kSlide:
      return "gymnasium_robotics.envs.fetch.slide:MujocoFetchSlideEnv";
  }
  return "";
}

// n copies of `value` as a Python list: "[v, v, v]"
std::string RepeatList(const std::string& value, int n) {
  std::string s = "[";
  for (int i = 0; i < n; ++i) s += (i ? ", " : "") + value;
  return s + "]";
}

// serialize_space(Box): type, dtype, shape, low, high, in that order
std::string BoxJson(const std::string& dtype, int n, const std::string& low,
                    const std::string& high) {
  return "{\"type\": \"Box\", \"dtype\": \"" + dtype + "\", \"shape\": [" + std::to_string(n) +
         "], \"low\": " + RepeatList(low, n) + ", \"high\": " + RepeatList(high, n) + "}";
}

// A list of `shape` filled with `value`, nested as numpy's tolist() nests it.
std::string NestedList(const std::string& value, const std::vector<int>& shape, size_t axis = 0) {
  if (axis == shape.size()) return value;
  const std::string inner = NestedList(value, shape, axis + 1);
  std::string s;
  s.reserve((inner.size() + 2) * static_cast<size_t>(shape[axis]) + 2);
  s += "[";
  for (int i = 0; i < shape[axis]; ++i) {
    if (i) s += ", ";
    s += inner;
  }
  return s + "]";
}

// serialize_space(Box) of an image Box
std::string ImageBoxJson(const std::string& dtype, const std::vector<int>& shape,
                         const std::string& low, const std::string& high) {
  std::string dims;
  for (size_t i = 0; i < shape.size(); ++i) dims += (i ? ", " : "") + std::to_string(shape[i]);
  return "{\"type\": \"Box\", \"dtype\": \"" + dtype + "\", \"shape\": [" + dims +
         "], \"low\": " + NestedList(low, shape) + ", \"high\": " + NestedList(high, shape) + "}";
}

}  // namespace

bool IsSupportedMinariVersion(const std::string& version) {
  static const char* const kVersions[] = {"0.4.0", "0.4.1", "0.4.2", "0.4.3",
                                          "0.5.0", "0.5.1", "0.5.2", "0.5.3"};
  for (const char* v : kVersions) {
    if (version == v) return true;
  }
  return false;
}

bool IsMinariDatasetId(const std::string& id) {
  // Minari's DATASET_ID_RE, ASCII \w, with the -vN its parse_dataset_id needs
  static const std::regex kId(R"(^(?:([-_\w][-_\w/]*[-_\w]+)/)?([-_\w]+?)-v(\d+)$)");
  std::smatch m;
  // no empty folder between slashes: "a//b-v0" would name the folder "a/b-v0"
  return std::regex_match(id, m, kId) && id.find("//") == std::string::npos;
}

void ValidateMinariDatasetId(const std::string& id) {
  if (!IsMinariDatasetId(id)) {
    throw UsageError("--minari: '" + id +
                     "' is not a Minari dataset id: expected (namespace/)name-vN of letters, "
                     "digits, '-' and '_', e.g. fetchscope/FetchPush/scripted-v0");
  }
}

std::filesystem::path MinariRoot(const std::string& flag) {
  // a root that is a file is named with where it came from; one that does not exist yet is
  // fine (writers make it, readers find no datasets there)
  auto checked = [](const std::filesystem::path& root, const std::string& from) {
    std::error_code ec;
    if (std::filesystem::exists(root, ec) && !std::filesystem::is_directory(root, ec)) {
      throw UsageError(from + " '" + root.string() +
                       "' is a file, not a folder: the datasets root must be a folder");
    }
    return root;
  };
  if (!flag.empty()) return checked(flag, "--minari-root");
  // set but empty counts as unset, as for every variable fetchscope reads
  if (const char* env = std::getenv("MINARI_DATASETS_PATH"); env && *env) {
    return checked(env, "MINARI_DATASETS_PATH");
  }
  const char* home = std::getenv("HOME");
  if (!home || !*home) {
    throw UsageError(
        "no datasets root: HOME is not set; give --minari-root DIR or set MINARI_DATASETS_PATH");
  }
  return std::filesystem::path(home) / ".minari" / "datasets";
}

std::string MinariNamespace(const std::string& id) {
  const size_t slash = id.rfind('/');
  return slash == std::string::npos ? std::string() : id.substr(0, slash);
}

std::string FetchObservationSpaceJson(int obs_dim) {
  const std::string goal = BoxJson("float64", 3, "-Infinity", "Infinity");
  return "{\"type\": \"Dict\", \"subspaces\": {\"achieved_goal\": " + goal +
         ", \"desired_goal\": " + goal +
         ", \"observation\": " + BoxJson("float64", obs_dim, "-Infinity", "Infinity") + "}}";
}

std::string FetchPixelObservationSpaceJson(int obs_dim, const PixelSpaces& pixels) {
  const std::string goal = BoxJson("float64", 3, "-Infinity", "Infinity");
  std::vector<std::string> names = pixels.cameras;
  std::sort(names.begin(), names.end());  // gymnasium's Dict sorts its keys
  const auto dict = [&](const std::string& box) {
    std::string s = "{\"type\": \"Dict\", \"subspaces\": {";
    for (size_t i = 0; i < names.size(); ++i) {
      s += (i ? ", " : "") + PythonJsonString(names[i]) + ": " + box;
    }
    return s + "}}";
  };
  const std::vector<int> hw = {pixels.height, pixels.width};
  std::string s = "{\"type\": \"Dict\", \"subspaces\": {\"achieved_goal\": " + goal;
  if (pixels.depth) s += ", \"depth\": " + dict(ImageBoxJson("float32", hw, "0.0", "Infinity"));
  s += ", \"desired_goal\": " + goal;
  if (pixels.rgb) {
    s += ", \"images\": " +
         dict(ImageBoxJson("uint8", {pixels.height, pixels.width, 3}, "0", "255"));
  }
  s += ", \"observation\": " + BoxJson("float64", obs_dim, "-Infinity", "Infinity");
  if (pixels.segmentation) {
    s += ", \"segmentation\": " +
         dict(ImageBoxJson("int32", hw, "-1", std::to_string(pixels.max_segment)));
  }
  return s + "}}";
}

std::string FetchActionSpaceJson() { return BoxJson("float32", 4, "-1.0", "1.0"); }

std::vector<std::string> FetchRequirements() {
  // reference/fetch-env.md: Gymnasium-Robotics 1.4.2's Fetch v4, on MuJoCo 2.2.2
  return {"gymnasium_robotics==1.4.2", "mujoco==2.2.2"};
}

std::string FetchEnvSpecJson(const EnvSpec& spec, int max_episode_steps) {
  if (max_episode_steps <= 0) max_episode_steps = spec.max_episode_steps;
  // dataclasses.asdict(EnvSpec) in field order, less namespace/name/version (gymnasium 1.x)
  return "{\"id\": " + PythonJsonString(spec.id) + ", \"entry_point\": \"" + EntryPoint(spec.task) +
         "\", \"reward_threshold\": null, \"nondeterministic\": false, \"max_episode_steps\": " +
         std::to_string(max_episode_steps) +
         ", \"order_enforce\": true, \"disable_env_checker\": false, \"kwargs\": "
         "{\"reward_type\": \"" +
         (spec.dense ? "dense" : "sparse") +
         "\"}, \"additional_wrappers\": [], \"vector_entry_point\": null}";
}

std::string PythonJsonString(const std::string& s) {
  // nlohmann's ensure_ascii escaping is Python's: \" \\ \b \f \n \r \t, \u00xx, \uXXXX pairs
  return nlohmann::json(s).dump(-1, ' ', true, nlohmann::json::error_handler_t::replace);
}

nlohmann::json ParsePythonJson(const std::string& text) {
  std::string out;
  out.reserve(text.size() + 16);
  bool in_string = false;
  for (size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    if (in_string) {
      out += c;
      if (c == '\\' && i + 1 < text.size()) {
        out += text[++i];
      } else if (c == '"') {
        in_string = false;
      }
      continue;
    }
    if (c == '"') {
      in_string = true;
      out += c;
    } else if (text.compare(i, 9, "-Infinity") == 0) {
      out += "\"-Infinity\"";
      i += 8;
    } else if (text.compare(i, 8, "Infinity") == 0) {
      out += "\"Infinity\"";
      i += 7;
    } else if (text.compare(i, 3, "NaN") == 0) {
      out += "\"NaN\"";
      i += 2;
    } else {
      out += c;
    }
  }
  return nlohmann::json::parse(out);
}

std::optional<double> PythonJsonNumber(const nlohmann::json& value) {
  if (value.is_number()) return value.get<double>();
  if (value.is_string()) {
    const std::string& s = value.get_ref<const std::string&>();
    if (s == "Infinity") return HUGE_VAL;
    if (s == "-Infinity") return -HUGE_VAL;
    if (s == "NaN") return std::nan("");
  }
  return std::nullopt;
}

void SilenceHdf5Errors() {
  H5dont_atexit();  // before libhdf5 initialises itself; ignored (an error) after that
  H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
}

std::string Hdf5SystemReason() {
  // the sec2 driver's description reads "... errno = 28, error message = 'No space left on
  // device' ...": the errno is the part we trust, its text comes from strerror here
  int found = 0;
  auto visit = [](unsigned, const H5E_error2_t* e, void* data) -> herr_t {
    const char* at = e->desc ? std::strstr(e->desc, "errno = ") : nullptr;
    if (at) {
      const int code = std::atoi(at + 8);
      if (code > 0) *static_cast<int*>(data) = code;
    }
    return 0;
  };
  H5Ewalk2(H5E_DEFAULT, H5E_WALK_DOWNWARD, visit, &found);
  return found > 0 ? std::string(std::strerror(found)) : std::string();
}

}  // namespace fetchscope
