// What a shared node does to a run (issue 35): a full disk under a dataset or under stdout, two
// runs racing for one folder or dataset id, Ctrl-C while an exec: policy is silent, compare's
// --out over a run, and non-finite numbers in a dataset. Each test runs the real binary and
// checks the exit code, the one line it prints and what is left on disk.
#include <gtest/gtest.h>
#include <sys/mount.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <csignal>
#include <filesystem>
#include <fstream>
#include <string>
#include <thread>
#include <vector>

#include "base/process.h"
#include "test_util.h"

namespace fetchscope::testing {
namespace {

namespace fs = std::filesystem;

std::string Bin() { return FETCHSCOPE_BIN; }

// A small file system that fills up: a 3 MiB tmpfs where this process may mount one (root with
// CAP_SYS_ADMIN), else nothing (the caller falls back to a file-size limit).
class SmallDisk {
 public:
  explicit SmallDisk(const fs::path& at) : at_(at) {
    fs::create_directories(at);
    mounted_ = mount("tmpfs", at.c_str(), "tmpfs", 0, "size=3m") == 0;
  }
  ~SmallDisk() {
    if (mounted_) umount2(at_.c_str(), MNT_DETACH);
  }
  bool mounted() const { return mounted_; }

 private:
  fs::path at_;
  bool mounted_ = false;
};

// The lines of `text` that are errors (fetchscope: error: ...)
std::vector<std::string> Errors(const std::string& text) {
  return LinesWith(text, "fetchscope: error:");
}

// Runs `args` against a full disk: on a 3 MiB tmpfs at `disk` when one can be mounted, else with
// a 1 MiB file-size limit (SIGXFSZ ignored, so writes fail with EFBIG). Returns the result and the
// words the one error line must hold.
CommandResult OnAFullDisk(const SmallDisk& disk, const std::string& args, std::string* expect) {
  if (disk.mounted()) {
    *expect = "no space left on device";
    return RunCommand(Bin() + " " + args);
  }
  *expect = "file too large";
  return RunCommand("trap '' XFSZ; ulimit -f 128; " + Bin() + " " + args);
}

// Fills the small disk but for `kib` KiB (128: about 10 FetchPush episodes of a dataset).
void FillBut(const SmallDisk& disk, const fs::path& at, int kib) {
  if (!disk.mounted()) return;
  std::ofstream(at / "filler", std::ios::binary) << std::string((3 << 20) - (kib << 10), 'x');
}

TEST(FullDisk, EveryMinariWriteFailsWithOneLineAndLeavesNothing) {
  TempDir tmp;
  const fs::path disk_dir = tmp.path() / "full";
  const SmallDisk disk(disk_dir);
  FillBut(disk, disk_dir, 128);
  // a run to export from, on the real disk
  const fs::path run = tmp.path() / "push.json";
  ASSERT_EQ(RunFetchscope("rollout --env-id FetchPush-v4 --episodes 20 --json-out " + run.string() +
                          " >/dev/null")
                .exit_code,
            0);
  const std::string root = (disk_dir / "ds").string();
  struct Case {
    const char* name;
    std::string args;
  };
  const std::vector<Case> cases = {
      {"rollout --minari", "rollout --env-id FetchPush-v4 --episodes 20 --minari-root " + root +
                               " --minari fs/roll-v0"},
      {"export", "export " + run.string() + " --minari-root " + root + " --minari fs/exp-v0"},
      // images: the workers' staging files and the dataset on the same full disk
      {"rollout --minari --obs-camera",
       "rollout --env-id FetchPush-v4 --episodes 20 --minari-root " + root +
           " --minari fs/pix-v0 --obs-camera external_camera_0 --obs-size 64x64 "
           "--obs-layers rgb,depth"},
      {"record --minari",
       "record --env-id FetchPush-v4 --episodes 20 --width 16 --height 16 "
       "--no-report --quiet --out " +
           (tmp.path() / "rec").string() + " --minari-root " + root + " --minari fs/rec-v0"},
  };
  for (const Case& c : cases) {
    std::string expect;
    const CommandResult r = OnAFullDisk(disk, c.args, &expect);
    EXPECT_EQ(r.exit_code, 1) << c.name << ": " << r.output;  // 139 was the crash at exit
    const std::vector<std::string> errors = Errors(r.output);
    ASSERT_EQ(errors.size(), 1u) << c.name << ": " << r.output;
    EXPECT_NE(errors[0].find(expect), std::string::npos) << c.name << ": " << errors[0];
    EXPECT_EQ(r.output.find("HDF5-DIAG"), std::string::npos) << c.name << ": " << r.output;
    // nothing half-written: no dataset, no temporary folder, no lock file
    std::error_code ec;
    std::vector<std::string> left;
    for (auto it = fs::recursive_directory_iterator(root, ec);
         !ec && it != fs::recursive_directory_iterator(); it.increment(ec)) {
      if (it->is_regular_file()) left.push_back(it->path().string());
    }
    EXPECT_TRUE(left.empty()) << c.name << " left " << left.front();
    fs::remove_all(root, ec);
  }
}

TEST(FullDisk, StandardOutputThatCannotBeWrittenIsAFailure) {
  // /dev/full: every write fails with ENOSPC
  for (const std::string& args :
       {std::string("datasets --json"), std::string("list-envs"), std::string("--help"),
        std::string("rollout --env-id FetchReach-v4 --episodes 3")}) {
    const CommandResult r = RunCommand("{ " + Bin() + " " + args + " >/dev/full; }");
    EXPECT_EQ(r.exit_code, 1) << args << ": " << r.output;
    EXPECT_EQ(Errors(r.output),
              std::vector<std::string>{
                  "fetchscope: error: cannot write to standard output: No space left on device"})
        << args << ": " << r.output;
  }
  // a closed stdout that is written to fails too (as coreutils' tools do); one never written is
  // fine
  const CommandResult closed = RunCommand("{ " + Bin() + " list-envs >&-; }");
  EXPECT_EQ(closed.exit_code, 1) << closed.output;
  EXPECT_NE(closed.output.find("cannot write to standard output: Bad file descriptor"),
            std::string::npos)
      << closed.output;
  TempDir tmp;
  const CommandResult quiet = RunCommand("{ " + Bin() +
                                         " record --env-id FetchReach-v4 --episodes 1 --steps 2 "
                                         "--width 32 --height 32 --quiet --out " +
                                         (tmp.path() / "r").string() + " >&-; }");
  EXPECT_EQ(quiet.exit_code, 0) << quiet.output;
}

TEST(FullDisk, JsonOnStdoutCutShortByAFullDiskFails) {
  TempDir tmp;
  const fs::path disk_dir = tmp.path() / "full";
  const SmallDisk disk(disk_dir);
  if (!disk.mounted()) GTEST_SKIP() << "cannot mount a tmpfs here (not root)";
  // 20 FetchPush episodes of JSON are about 1.4 MB: cut where 128 KiB are left
  FillBut(disk, disk_dir, 128);
  const fs::path err = tmp.path() / "err";
  const CommandResult r =
      RunCommand("{ " + Bin() + " rollout --env-id FetchPush-v4 --episodes 20 >" +
                 (disk_dir / "out.json").string() + " 2>" + err.string() + "; }");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_EQ(Errors(ReadFile(err)),
            std::vector<std::string>{
                "fetchscope: error: cannot write to standard output: No space left on device"})
      << ReadFile(err);
}

// Two `record` runs started at the same moment into one --out: one records, the other is refused
// at once (the lock, naming the first one's PID, or its manifest, when it was already there),
// and the run that recorded is whole. 20 rounds.
TEST(TwoWriters, OnlyOneRunWritesAFolder) {
  TempDir tmp;
  int locked = 0;
  for (int round = 0; round < 20; ++round) {
    const fs::path out = tmp.path() / ("race" + std::to_string(round));
    const std::string args =
        "record --env-id FetchReach-v4 --episodes 2 --steps 2 --width 32 "
        "--height 32 --jobs 2 --quiet --out " +
        out.string();
    const fs::path log_a = tmp.path() / "a.log", log_b = tmp.path() / "b.log";
    const pid_t a = SpawnFetchscope(args, log_a);
    const pid_t b = SpawnFetchscope(args, log_b);
    const int exit_a = WaitExit(a), exit_b = WaitExit(b);
    const std::string text_a = ReadFile(log_a), text_b = ReadFile(log_b);
    ASSERT_TRUE((exit_a == 0) != (exit_b == 0))
        << "round " << round << ": " << exit_a << " " << text_a << " / " << exit_b << " " << text_b;
    const std::string& loser = exit_a == 0 ? text_b : text_a;
    const pid_t winner = exit_a == 0 ? a : b;
    EXPECT_EQ(exit_a == 0 ? exit_b : exit_a, 2) << loser;
    ASSERT_EQ(Errors(loser).size(), 1u) << loser;
    if (loser.find("is being written by another fetchscope") != std::string::npos) {
      ++locked;
      EXPECT_NE(loser.find("(PID " + std::to_string(winner) + ")"), std::string::npos) << loser;
    } else {
      EXPECT_NE(loser.find("already holds a record run"), std::string::npos) << loser;
    }
    // the run is whole: every file its manifest lists is there, and no temporary is left
    const nlohmann::json m = nlohmann::json::parse(ReadFile(out / "manifest.json"));
    ASSERT_EQ(m["episodes"].size(), 2u);
    for (const auto& e : m["episodes"]) {
      for (const char* key : {"video", "trajectory", "contact_sheet"}) {
        if (e.contains(key) && e[key].is_string()) {
          EXPECT_TRUE(fs::exists(out / e[key].get<std::string>())) << e[key];
        }
      }
    }
    for (const auto& entry : fs::directory_iterator(out)) {
      EXPECT_NE(entry.path().filename().string()[0], '.') << entry.path();
    }
  }
  std::printf("refused by the lock in %d of 20 rounds (the rest by the first run's manifest)\n",
              locked);
}

// A held folder or dataset id, whoever holds it (here flock(1), as another fetchscope would):
// record, --overwrite, merge-manifests and the Minari writers refuse it at once, naming the PID.
TEST(TwoWriters, AHeldFolderOrDatasetIdIsRefusedNamingTheHolder) {
  if (RunCommand("command -v flock").exit_code != 0) GTEST_SKIP() << "no flock(1)";
  TempDir tmp;
  const fs::path run = tmp.path() / "run";
  ASSERT_EQ(RunFetchscope("record --env-id FetchReach-v4 --episodes 1 --steps 3 --width 32 "
                          "--height 32 --quiet --out " +
                          run.string())
                .exit_code,
            0);
  const fs::path root = tmp.path() / "datasets";
  fs::create_directories(root / "fs");
  // the holders: flock on the folder, and on the dataset id's lock file
  const pid_t holder = fork();
  if (holder == 0) {
    setpgid(0, 0);  // flock's child (sleep) holds the lock too: both are killed as a group
    execl("/usr/bin/flock", "flock", run.c_str(), "sleep", "60", static_cast<char*>(nullptr));
    _exit(127);
  }
  const fs::path id_lock = root / "fs" / ".held-v0.lock";
  const pid_t id_holder = fork();
  if (id_holder == 0) {
    setpgid(0, 0);
    execl("/usr/bin/flock", "flock", id_lock.c_str(), "sleep", "60", static_cast<char*>(nullptr));
    _exit(127);
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(500));  // flock has locked
  struct Case {
    std::string args;
    pid_t pid;
  };
  const std::vector<Case> cases = {
      {"record --env-id FetchReach-v4 --episodes 1 --steps 3 --overwrite --out " + run.string(),
       holder},
      {"record --env-id FetchReach-v4 --episodes 2 --steps 3 --resume --out " + run.string(),
       holder},
      {"merge-manifests " + run.string(), holder},
      {"rollout --env-id FetchReach-v4 --episodes 1 --minari-root " + root.string() +
           " --minari fs/held-v0",
       id_holder},
  };
  for (const Case& c : cases) {
    const auto t0 = std::chrono::steady_clock::now();
    const CommandResult r = RunFetchscope(c.args + " 2>&1");
    const double seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    EXPECT_EQ(r.exit_code, 2) << c.args << ": " << r.output;
    const std::vector<std::string> errors = Errors(r.output);
    ASSERT_EQ(errors.size(), 1u) << c.args << ": " << r.output;
    EXPECT_NE(errors[0].find("is being written by another fetchscope (PID " +
                             std::to_string(c.pid) + ")"),
              std::string::npos)
        << errors[0];
    EXPECT_LT(seconds, 20) << c.args << ": refused at once, not after the run";
  }
  kill(-holder, SIGTERM);
  kill(-id_holder, SIGTERM);
  WaitExit(holder);
  WaitExit(id_holder);
  // released by the holder's death: both work now, and the id's lock file is gone afterwards
  EXPECT_EQ(RunFetchscope("record --env-id FetchReach-v4 --episodes 1 --steps 3 --width 32 "
                          "--height 32 --quiet --overwrite --out " +
                          run.string())
                .exit_code,
            0);
  const CommandResult rollout =
      RunFetchscope("rollout --env-id FetchReach-v4 --episodes 1 --minari-root " + root.string() +
                    " --minari fs/held-v0 2>&1 >/dev/null");
  EXPECT_EQ(rollout.exit_code, 0) << rollout.output;
  EXPECT_FALSE(fs::exists(id_lock));
}

// Two dataset writes of one id at once: one writes it, the other is refused (the lock, or the
// dataset already there), and the dataset is whole.
TEST(TwoWriters, OnlyOneRunWritesADatasetId) {
  TempDir tmp;
  const std::string args = "rollout --env-id FetchReach-v4 --episodes 10 --minari-root " +
                           (tmp.path() / "ds").string() + " --minari fs/race-v0";
  for (int round = 0; round < 3; ++round) {
    std::error_code ec;
    fs::remove_all(tmp.path() / "ds", ec);
    const fs::path log_a = tmp.path() / "a.log", log_b = tmp.path() / "b.log";
    const pid_t a = SpawnFetchscope(args, log_a);
    const pid_t b = SpawnFetchscope(args, log_b);
    const int exit_a = WaitExit(a), exit_b = WaitExit(b);
    const std::string loser = exit_a == 0 ? ReadFile(log_b) : ReadFile(log_a);
    ASSERT_TRUE((exit_a == 0) != (exit_b == 0)) << exit_a << " " << exit_b << ": " << loser;
    EXPECT_EQ(exit_a == 0 ? exit_b : exit_a, 2) << loser;
    ASSERT_EQ(Errors(loser).size(), 1u) << loser;
    EXPECT_TRUE(loser.find("is being written by another fetchscope") != std::string::npos ||
                loser.find("already exists") != std::string::npos)
        << loser;
    const fs::path data = tmp.path() / "ds" / "fs" / "race-v0" / "data";
    EXPECT_TRUE(fs::exists(data / "main_data.hdf5"));
    EXPECT_TRUE(fs::exists(data / "metadata.json"));
    EXPECT_FALSE(fs::exists(tmp.path() / "ds" / "fs" / ".race-v0.lock"));
  }
}

// Ctrl-C while an exec: policy is silent: fetchscope ends the wait at once (exit 130 within a
// second, where it used to wait for --exec-timeout), keeps the episode in progress as incomplete,
// and prints a command to record the rest that pastes into a shell as it is.
TEST(SilentPolicy, CtrlCEndsTheWaitAtOnceAndThePrintedCommandPastes) {
  TempDir tmp;
  const fs::path dir = tmp.path() / "policy dir";  // a space: the command must be quoted
  fs::create_directories(dir);
  const fs::path policy = dir / "hang.py";
  std::ofstream(policy) << "import json, os, sys, time\n"
                           "n = 0\n"
                           "for line in sys.stdin:\n"
                           "    n += 1\n"
                           "    if n > 8 and os.path.exists(" +
                               nlohmann::json((dir / "hang").string()).dump() +
                               "):\n"
                               "        time.sleep(1000)\n"
                               "    print(json.dumps([0.5, 0.0, 0.0, 0.0]), flush=True)\n";
  std::ofstream(dir / "hang") << "";
  const fs::path out = tmp.path() / "run";
  const fs::path log = tmp.path() / "log";
  const pid_t pid = SpawnFetchscope(
      "record --env-id FetchReach-v4 --episodes 3 --steps 6 "
      "--width 48 --height 48 --exec-timeout 60 --policy " +
          ShellQuote("exec:python3 " + ShellQuote(policy.string())) + " --out " + out.string(),
      log);
  // wait until the policy has answered 8 steps and gone silent
  for (int i = 0; i < 300 && ReadFile(log).find("progress 1/3") == std::string::npos; ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(700));
  const auto t0 = std::chrono::steady_clock::now();
  kill(pid, SIGINT);
  const int code = WaitExit(pid);
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const std::string text = ReadFile(log);
  EXPECT_EQ(code, 130) << text;
  EXPECT_LT(seconds, 1.0) << text;
  const nlohmann::json m = nlohmann::json::parse(ReadFile(out / "manifest.json"));
  EXPECT_TRUE(m["interrupted"].get<bool>());
  ASSERT_EQ(m["episodes"].size(), 2u) << m["episodes"].dump();
  EXPECT_FALSE(m["episodes"][1]["complete"].get<bool>()) << "the episode in progress is kept";
  EXPECT_EQ(m["incomplete_episodes"], nlohmann::json::array({1}));
  // the interrupted episode is kept but never counted as done in the progress lines
  EXPECT_EQ(text.find("progress 2/3 episodes"), std::string::npos) << text;
  // the printed command, pasted into a shell as it is, records the rest
  const std::string marker = "record: to record the rest, run: ";
  const size_t at = text.find(marker);
  ASSERT_NE(at, std::string::npos) << text;
  const std::string command =
      text.substr(at + marker.size(), text.find('\n', at) - at - marker.size());
  fs::remove(dir / "hang");
  const CommandResult rest = RunCommand(command + " 2>&1");
  EXPECT_EQ(rest.exit_code, 0) << command << "\n" << rest.output;
  const nlohmann::json whole = nlohmann::json::parse(ReadFile(out / "manifest.json"));
  EXPECT_FALSE(whole["interrupted"].get<bool>());
  EXPECT_EQ(whole["episodes"].size(), 3u);
}

TEST(CompareOut, ARunFolderIsRefusedAndAFailureWritesNothing) {
  TempDir tmp;
  const fs::path a = tmp.path() / "a", b = tmp.path() / "b";
  const std::string common =
      " --env-id FetchReach-v4 --episodes 1 --steps 8 --width 64 "
      "--height 64 --quiet --out ";
  ASSERT_EQ(RunFetchscope("record" + common + a.string()).exit_code, 0);
  ASSERT_EQ(RunFetchscope("record --policy scripted" + common + b.string()).exit_code, 0);
  const std::string report_a = ReadFile(a / "index.html");
  for (const fs::path& out : {a, b, fs::path(a.string() + "/")}) {
    const CommandResult r = RunFetchscope("compare " + a.string() + " " + b.string() + " --out " +
                                          out.string() + " 2>&1");
    EXPECT_EQ(r.exit_code, 2) << r.output;
    ASSERT_EQ(Errors(r.output).size(), 1u) << r.output;
    EXPECT_NE(r.output.find("choose a new folder"), std::string::npos) << r.output;
  }
  // a third run's folder
  const fs::path c = tmp.path() / "c";
  ASSERT_EQ(RunFetchscope("record" + common + c.string()).exit_code, 0);
  const CommandResult into_c =
      RunFetchscope("compare " + a.string() + " " + b.string() + " --out " + c.string() + " 2>&1");
  EXPECT_EQ(into_c.exit_code, 2) << into_c.output;
  EXPECT_NE(into_c.output.find("holds a record run"), std::string::npos) << into_c.output;
  EXPECT_EQ(ReadFile(a / "index.html"), report_a);
  EXPECT_FALSE(fs::exists(a / "compare.json"));
  // B's video cut short in the middle: one line, no libav chatter, nothing written (a new
  // folder is removed again, an existing one gets nothing new)
  const std::string video = ReadFile(b / "episode_000.mp4");
  std::ofstream(b / "episode_000.mp4", std::ios::binary | std::ios::trunc)
      << video.substr(0, video.size() * 2 / 3);
  const fs::path existing = tmp.path() / "existing";
  fs::create_directories(existing);
  std::ofstream(existing / "notes.txt") << "mine\n";
  for (const fs::path& out : {tmp.path() / "new", existing}) {
    const CommandResult r = RunFetchscope("compare " + a.string() + " " + b.string() + " --out " +
                                          out.string() + " 2>&1");
    EXPECT_EQ(r.exit_code, 2) << r.output;
    EXPECT_EQ(LineCount(r.output), 1) << r.output;
    EXPECT_EQ(Errors(r.output).size(), 1u) << r.output;
    EXPECT_EQ(r.output.find("[h264"), std::string::npos) << r.output;
    EXPECT_EQ(r.output.find("[mov"), std::string::npos) << r.output;
  }
  EXPECT_FALSE(fs::exists(tmp.path() / "new"));
  EXPECT_EQ(FilesIn(existing), std::set<std::string>{"notes.txt"});
}

// NaN or an infinity in a dataset: refused with one line naming the episode, the step and the
// field, before anything is written (MuJoCo used to print "unstable" and the JSON got "nan").
TEST(NonFinite, DatasetsWithNanOrInfinityAreRefusedNamingWhere) {
  const std::string python = PythonWithH5py();
  if (python.empty()) GTEST_SKIP() << "python3 with h5py and numpy is needed to plant a NaN";
  TempDir tmp;
  const fs::path root = tmp.path() / "ds";
  ASSERT_EQ(RunFetchscope("rollout --env-id FetchPush-v4 --episodes 2 --minari-root " +
                          root.string() + " --minari fs/nan-v0 >/dev/null")
                .exit_code,
            0);
  const fs::path file = root / "fs" / "nan-v0" / "data" / "main_data.hdf5";
  struct Case {
    const char* key;
    const char* index;
    const char* value;
    const char* expect;
  };
  for (const Case& c :
       {Case{"episode_1/actions", "3, 2", "np.nan", "episode_1: step 3: actions[2] is nan"},
        Case{"episode_0/observations/observation", "0, 4", "np.inf",
             "episode_0: the reset: observations/observation[4] is inf"},
        Case{"episode_1/observations/desired_goal", "5, 1", "-np.inf",
             "episode_1: step 4: observations/desired_goal[1] is -inf"}}) {
    const fs::path copy = tmp.path() / "copy";
    std::error_code ec;
    fs::remove_all(copy, ec);
    fs::copy(root, copy, fs::copy_options::recursive);
    const fs::path planted = copy / "fs" / "nan-v0" / "data" / "main_data.hdf5";
    ASSERT_EQ(RunCommand(python +
                         " -c \"import h5py, numpy as np\n"
                         "f = h5py.File('" +
                         planted.string() + "', 'r+')\nd = f['" + c.key + "']\nx = d[()]\nx[" +
                         c.index + "] = " + c.value + "\nd[...] = x\nf.close()\"")
                  .exit_code,
              0);
    for (const std::string& command :
         {"record --from fs/nan-v0 --minari-root " + copy.string() + " --quiet --out " +
              (tmp.path() / "rec").string(),
          "record --from " + planted.string() + " --format none --quiet --out " +
              (tmp.path() / "rec").string()}) {
      const CommandResult r = RunFetchscope(command + " 2>&1");
      EXPECT_EQ(r.exit_code, 1) << command << ": " << r.output;
      ASSERT_EQ(Errors(r.output).size(), 1u) << command << ": " << r.output;
      EXPECT_NE(r.output.find(c.expect), std::string::npos) << command << ": " << r.output;
      EXPECT_NE(r.output.find("a replay needs finite numbers"), std::string::npos) << r.output;
      EXPECT_EQ(r.output.find("unstable"), std::string::npos) << r.output;
      EXPECT_FALSE(fs::exists(tmp.path() / "rec"));
    }
  }
}

}  // namespace
}  // namespace fetchscope::testing
