// base/process.h: children start from an exact argv or a function, in their own process group,
// die with their parent, talk in JSON lines; a wait ends at once on a stop signal; and how a
// child ended is classified (exited, signalled, interrupted).
#include "base/process.h"

#include <gtest/gtest.h>
#include <pthread.h>
#include <signal.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cstdlib>
#include <fstream>
#include <string>
#include <thread>
#include <vector>

#include "base/stop_signal.h"
#include "tests/test_util.h"

namespace fetchscope {
namespace {

using Clock = std::chrono::steady_clock;

double Since(Clock::time_point t) {
  return std::chrono::duration<double>(Clock::now() - t).count();
}

// Everything `child` writes on its stdout (or socket), up to end of file.
std::string ReadAll(ChildProcess& child) {
  std::string text;
  while (child.channel().ReadSome()) {
    while (std::optional<std::string> line = child.channel().TakeLine()) text += *line + "\n";
  }
  return text;
}

// True while `pid` exists and is not a zombie (a zombie is dead, only not yet reaped).
bool Alive(pid_t pid) {
  std::ifstream stat("/proc/" + std::to_string(pid) + "/stat");
  std::string text((std::istreambuf_iterator<char>(stat)), std::istreambuf_iterator<char>());
  if (text.empty()) return false;
  const size_t paren = text.rfind(')');
  return paren != std::string::npos && paren + 2 < text.size() && text[paren + 2] != 'Z';
}

// Waits up to `seconds` for `pid` to be gone.
bool GoneWithin(pid_t pid, double seconds) {
  const auto start = Clock::now();
  while (Alive(pid)) {
    if (Since(start) > seconds) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  return true;
}

SpawnOptions PipeOut() {
  SpawnOptions options;
  options.out = Stdio::kPipe;
  return options;
}

TEST(Process, SpawnRunsTheExactArgvWithNoShell) {
  ChildProcess child =
      ChildProcess::Spawn({"printf", "%s|%s|%s\n", "two words", "$HOME", "*"}, PipeOut());
  EXPECT_EQ(ReadAll(child), "two words|$HOME|*\n");  // no splitting, expansion or globbing
  EXPECT_TRUE(child.Wait().ok());
  EXPECT_FALSE(child.running());
}

TEST(Process, SpawnPassesTheEnvironmentItIsGiven) {
  SpawnOptions options = PipeOut();
  options.env = std::vector<std::string>{"ONLY=this", "PATH=/usr/bin:/bin"};
  ChildProcess child = ChildProcess::Spawn({"/usr/bin/env"}, options);
  EXPECT_EQ(ReadAll(child), "ONLY=this\nPATH=/usr/bin:/bin\n");
  EXPECT_TRUE(child.Wait().ok());
}

TEST(Process, AProgramThatIsNotThereExitsWith127) {
  SpawnOptions options;
  options.err = Stdio::kNull;
  ChildProcess child = ChildProcess::Spawn({"/nonexistent/program"}, options);
  const ChildExit status = child.Wait();
  EXPECT_EQ(status.code, 127);
  EXPECT_FALSE(status.ok());
  EXPECT_EQ(FindProgram("no-such-program-fetchscope"), "");
  EXPECT_NE(FindProgram("sh"), "");
}

// JSON lines both ways through a program's stdin and stdout, a line longer than a pipe holds
// included: every line comes back whole and in order.
TEST(Process, JsonLinesRoundTripThroughAProgram) {
  SpawnOptions options = PipeOut();
  options.in = Stdio::kPipe;
  ChildProcess child = ChildProcess::Spawn({"cat"}, options);
  const nlohmann::json small = {{"t", 0}, {"observation", {1.5, -2, 3}}};
  const nlohmann::json big = {{"t", 1}, {"text", std::string(200000, 'x')}};
  // the big line fills the pipe both ways: the reader must run while the writer writes
  std::thread writer([&] {
    EXPECT_TRUE(child.channel().Send(small));
    EXPECT_TRUE(child.channel().Send(big));
    child.channel().CloseOutput();
  });
  std::vector<nlohmann::json> got;
  while (std::optional<nlohmann::json> message = child.channel().Receive()) {
    got.push_back(*message);
  }
  writer.join();
  ASSERT_EQ(got.size(), 2u);
  EXPECT_EQ(got[0], small);
  EXPECT_EQ(got[1], big);
  EXPECT_TRUE(child.Wait().ok());
}

TEST(Process, JsonLinesRoundTripWithAForkedFunction) {
  ChildProcess child = ChildProcess::Fork([](LineChannel& parent) {
    while (std::optional<nlohmann::json> message = parent.Receive()) {
      if (message->at("t") == "quit") return 3;
      parent.Send({{"t", "twice"}, {"n", 2 * message->at("n").get<int>()}});
    }
    return 1;
  });
  for (int n : {1, 20, -7}) {
    ASSERT_TRUE(child.channel().Send({{"t", "n"}, {"n", n}}));
    const std::optional<nlohmann::json> answer = child.channel().Receive();
    ASSERT_TRUE(answer);
    EXPECT_EQ(answer->at("n"), 2 * n);
  }
  child.channel().Send({{"t", "quit"}});
  const ChildExit status = child.Wait();
  EXPECT_TRUE(status.exited());
  EXPECT_EQ(status.code, 3);  // what the function returned
}

// A terminal's Ctrl-C goes to the foreground process group: children in groups of their own
// never get it, only the parent, which decides.
TEST(Process, ChildrenRunInTheirOwnProcessGroup) {
  ChildProcess spawned = ChildProcess::Spawn({"sleep", "30"});
  ChildProcess forked = ChildProcess::Fork([](LineChannel&) {
    pause();
    return 0;
  });
  for (const ChildProcess* child : {&spawned, &forked}) {
    EXPECT_EQ(getpgid(child->pid()), child->pid());
    EXPECT_NE(getpgid(child->pid()), getpgrp());
  }
}

// The destructor kills the whole group, so a shell's own children go too, and reaps.
TEST(Process, DestructorKillsTheGroupAndReaps) {
  pid_t shell = -1, grandchild = -1;
  {
    ChildProcess child = ChildProcess::Spawn({"sh", "-c", "sleep 30 & echo $!; wait"}, PipeOut());
    shell = child.pid();
    ASSERT_TRUE(child.channel().ReadSome());
    const std::optional<std::string> line = child.channel().TakeLine();
    ASSERT_TRUE(line);
    grandchild = std::stoi(*line);
    EXPECT_TRUE(Alive(grandchild));
  }
  EXPECT_FALSE(Alive(shell));
  EXPECT_TRUE(GoneWithin(grandchild, 2)) << "the shell's child outlived the handle";
}

// A parent killed with SIGKILL cannot clean up: its children die with it (PR_SET_PDEATHSIG).
TEST(Process, ChildDiesWithItsParent) {
  ChildProcess parent = ChildProcess::Fork([](LineChannel& channel) {
    ChildProcess child = ChildProcess::Spawn({"sleep", "30"});
    channel.Send({{"pid", child.pid()}});
    pause();
    return 0;
  });
  const std::optional<nlohmann::json> message = parent.channel().Receive();
  ASSERT_TRUE(message);
  const pid_t child = message->at("pid").get<pid_t>();
  EXPECT_TRUE(Alive(child));
  parent.Signal(SIGKILL);
  EXPECT_EQ(parent.Wait().signal, SIGKILL);
  EXPECT_TRUE(GoneWithin(child, 2)) << "the child outlived its parent";
}

// a printed command line pastes: every word comes back from the shell as it was
TEST(Process, ShellQuoteGivesEachWordBackThroughTheShell) {
  EXPECT_EQ(ShellQuote("record"), "record");
  EXPECT_EQ(ShellQuote("--policy=replay:/tmp/a_b-1.json"), "--policy=replay:/tmp/a_b-1.json");
  EXPECT_EQ(ShellQuote(""), "''");
  EXPECT_EQ(ShellQuote("exec:python3 /x/hang.py"), "'exec:python3 /x/hang.py'");
  for (const std::string& word : {std::string("it's"), std::string("a b\tc"), std::string("$HOME"),
                                  std::string("`id`;rm -rf /"), std::string("*"),
                                  std::string("new\nline"), std::string("\"quoted\"")}) {
    const auto r = testing::RunCommand("printf '%s' " + ShellQuote(word));
    EXPECT_EQ(r.output, word) << ShellQuote(word);
  }
}

TEST(Process, ExitClassification) {
  ChildProcess three = ChildProcess::Spawn({"sh", "-c", "exit 3"});
  const ChildExit exited = three.Wait();
  EXPECT_TRUE(exited.exited());
  EXPECT_FALSE(exited.ok());
  EXPECT_FALSE(exited.interrupted());
  EXPECT_EQ(exited.code, 3);
  EXPECT_EQ(exited.ShellCode(), 3);
  EXPECT_EQ(exited.Describe(), "exited with status 3");

  for (int sig : {SIGINT, SIGTERM, SIGHUP}) {
    ChildProcess child = ChildProcess::Spawn({"sleep", "30"});
    child.SignalGroup(sig);
    const ChildExit status = child.Wait();
    EXPECT_FALSE(status.exited()) << sig;
    EXPECT_EQ(status.signal, sig);
    EXPECT_TRUE(status.interrupted()) << "stopped by " << sig << " is no failure";
    EXPECT_EQ(status.ShellCode(), 128 + sig);
  }

  ChildProcess aborted = ChildProcess::Fork([](LineChannel&) -> int { std::abort(); });
  const ChildExit crash = aborted.Wait();
  EXPECT_EQ(crash.signal, SIGABRT);
  EXPECT_FALSE(crash.interrupted());
  EXPECT_EQ(crash.Describe(), "died of signal 6 (SIGABRT: Aborted)");

  ChildProcess killed = ChildProcess::Spawn({"sleep", "30"});
  killed.Kill();
  EXPECT_FALSE(killed.running());
}

// A stop signal ends WaitForInput at once, whichever thread the kernel gives the signal to;
// one that came before the wait ends it before it starts; without watch_stop it does not.
TEST(Process, WaitEndsAtOnceOnAStopSignal) {
  int fds[2];
  ASSERT_EQ(pipe(fds), 0);
  UniqueFd read_end(fds[0]), write_end(fds[1]);
  std::vector<pollfd> poll_fds = {{read_end.get(), POLLIN, 0}};

  for (int sig : {SIGINT, SIGTERM}) {
    InstallStopSignals();
    Clock::time_point sent;
    std::thread sender([&] {
      std::this_thread::sleep_for(std::chrono::milliseconds(200));
      sent = Clock::now();
      kill(getpid(), sig);
    });
    const auto start = Clock::now();
    const WaitEnd end = WaitForInput(&poll_fds, 10000);
    const double latency = Since(sent);
    sender.join();
    EXPECT_EQ(end, WaitEnd::kStop);
    EXPECT_EQ(StopSignal(), sig);
    EXPECT_LT(Since(start), 2.0);
    // generous bounds (CI runs this under ASan, two tests at a time, on 2 cores): what matters is
    // that the 10 s wait ends on the signal
    EXPECT_LT(latency, 1.0) << "a stop must end the wait, not its timeout";
    std::printf("stop latency (signal %d): %.3f ms\n", sig, 1000 * latency);
  }

  // already requested: at once, without waiting
  const auto start = Clock::now();
  EXPECT_EQ(WaitForInput(&poll_fds, 10000), WaitEnd::kStop);
  EXPECT_LT(Since(start), 1.0);
  // not watched: the wait runs its course, and input still ends it
  EXPECT_EQ(WaitForInput(&poll_fds, 50, /*watch_stop=*/false), WaitEnd::kNone);
  ASSERT_EQ(write(write_end.get(), "x", 1), 1);
  EXPECT_EQ(WaitForInput(&poll_fds, 1000, /*watch_stop=*/false), WaitEnd::kReady);
  EXPECT_TRUE(poll_fds[0].revents & POLLIN);
  InstallStopSignals();  // clears the request
  EXPECT_EQ(StopSignal(), 0);
  EXPECT_EQ(WaitForInput(&poll_fds, 1000), WaitEnd::kReady);
}

// A signal the kernel gives to another thread (here aimed at one with pthread_kill) still ends
// the wait at once: the handler writes the stop self-pipe, which the wait watches.
TEST(Process, WaitEndsOnAStopTakenByAnotherThread) {
  InstallStopSignals();
  std::atomic<bool> done{false};
  std::thread taker([&] {
    while (!done) std::this_thread::sleep_for(std::chrono::milliseconds(1));
  });
  WaitEnd end = WaitEnd::kNone;
  double took = 0;
  std::thread waiter([&] {
    std::vector<pollfd> none;
    const auto start = Clock::now();
    end = WaitForInput(&none, 10000);
    took = Since(start);
  });
  std::this_thread::sleep_for(std::chrono::milliseconds(100));
  const auto sent = Clock::now();
  pthread_kill(taker.native_handle(), SIGINT);
  waiter.join();
  const double latency = Since(sent);
  done = true;
  taker.join();
  EXPECT_EQ(end, WaitEnd::kStop);
  EXPECT_EQ(StopSignal(), SIGINT);
  EXPECT_LT(took, 2.0);
  EXPECT_LT(latency, 1.0);
  InstallStopSignals();
}

}  // namespace
}  // namespace fetchscope
