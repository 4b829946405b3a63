// CLI11's parse errors rewritten for people: "The following arguments were not expected: 3
// --episode" becomes "unknown option '--episode' (did you mean '--episodes'?)".
#include "cli/parse_errors.h"

#include <cstdlib>
#include <string>
#include <vector>

#include "base/suggest.h"

namespace fetchscope::cli {
namespace {

// The subcommand that argv names (the deepest one), and the index of the first argument after
// its name; `app` itself when argv names none.
const CLI::App* NamedCommand(const CLI::App& app, int argc, const char* const* argv, int* next) {
  const CLI::App* command = &app;
  int i = 1;
  for (; i < argc && argv[i][0] != '-'; ++i) {
    const CLI::App* sub = nullptr;
    for (const CLI::App* s : command->get_subcommands({})) {
      if (s->get_name() == argv[i]) sub = s;
    }
    if (!sub) break;
    command = sub;
  }
  *next = i;
  return command;
}

// "fetchscope record": the command's full name.
std::string CommandPath(const CLI::App* command) {
  std::string path;
  for (const CLI::App* a = command; a->get_parent() != nullptr; a = a->get_parent()) {
    path = a->get_name() + (path.empty() ? "" : " ") + path;
  }
  return "fetchscope" + (path.empty() ? "" : " " + path);
}

// Every spelling of the command's options ("--episodes", "-o"), and its parents' (--help).
std::vector<std::string> OptionNames(const CLI::App* command) {
  std::vector<std::string> names;
  for (const CLI::App* a = command; a != nullptr; a = a->get_parent()) {
    for (const CLI::Option* opt : a->get_options()) {
      for (const std::string& n : opt->get_lnames()) names.push_back("--" + n);
      for (const std::string& n : opt->get_snames()) names.push_back("-" + n);
    }
  }
  return names;
}

const CLI::Option* FindOption(const CLI::App* command, const std::string& name) {
  for (const CLI::App* a = command; a != nullptr; a = a->get_parent()) {
    if (const CLI::Option* opt = a->get_option_no_throw(name)) return opt;
  }
  return nullptr;
}

bool StartsWith(const std::string& text, const std::string& prefix) {
  return text.compare(0, prefix.size(), prefix) == 0;
}

// "--episodes: At Most 1 required ..." -> "--episodes"; "" when the message names no option.
std::string LeadingOption(const std::string& message) {
  if (!StartsWith(message, "-")) return "";
  const size_t colon = message.find(':');
  return colon == std::string::npos ? "" : message.substr(0, colon);
}

// What a value of `opt` has to be, from its CLI11 type name.
std::string ValueKind(const CLI::Option* opt) {
  const std::string type = opt ? opt->get_type_name() : "";
  if (type.find("UINT") != std::string::npos || type.find("INT") != std::string::npos)
    return "a whole number";
  if (type.find("FLOAT") != std::string::npos || type.find("NUMBER") != std::string::npos)
    return "a number";
  return "a value it accepts";
}

// Extras: the first argument that is an unknown option, an option with an empty "=" value, or
// else the first stray word.
std::string ExtrasMessage(const CLI::App* command, int first, int argc, const char* const* argv) {
  std::string stray;
  for (int i = first; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg.size() < 2 || arg[0] != '-' || (arg[1] >= '0' && arg[1] <= '9') || arg[1] == '.') {
      continue;  // a value (negative numbers included)
    }
    if (arg == "--") break;
    const size_t eq = arg.find('=');
    const std::string name = arg.substr(0, eq);
    const CLI::Option* opt = FindOption(command, name);
    if (!opt) {
      // name the value it came with too ("--seed abc" to a command without --seed)
      std::string value;
      if (eq != std::string::npos) {
        value = arg.substr(eq + 1);
      } else if (i + 1 < argc && argv[i + 1][0] != '-') {
        value = argv[i + 1];
      }
      return "unknown option '" + name + "'" + (value.empty() ? "" : " (given '" + value + "')") +
             DidYouMean(name, OptionNames(command));
    }
    if (eq != std::string::npos && eq + 1 == arg.size() && opt->get_expected_max() != 0) {
      return name + " needs a value after '=' (" + name + "=VALUE or " + name + " VALUE)";
    }
  }
  // no option to blame: a word where none was expected (an option's value given twice, a
  // value without its option)
  for (int i = first; i < argc; ++i) {
    if (argv[i][0] != '-') stray = argv[i];
  }
  return stray.empty() ? "unexpected arguments" : "unexpected argument '" + stray + "'";
}

}  // namespace

std::string ParseErrorMessage(const CLI::App& app, const CLI::ParseError& error, int argc,
                              const char* const* argv) {
  int next = 1;
  const CLI::App* command = NamedCommand(app, argc, argv, &next);
  // CLI11 reports a misspelt command as "A subcommand is required" or as an extra: name it
  if (next < argc && argv[next][0] != '-' && !command->get_subcommands({}).empty()) {
    std::string names;
    std::vector<std::string> list;
    for (const CLI::App* sub : command->get_subcommands({})) {
      names += (names.empty() ? "" : ", ") + sub->get_name();
      list.push_back(sub->get_name());
    }
    return "unknown command '" + std::string(argv[next]) + "'" + DidYouMean(argv[next], list) +
           ": accepted: " + names;
  }
  const std::string help = " (see " + CommandPath(command) + " --help)";
  const std::string what = error.what();
  const std::string option = LeadingOption(what);
  if (dynamic_cast<const CLI::ExtrasError*>(&error)) {
    return ExtrasMessage(command, next, argc, argv) + help;
  }
  if (dynamic_cast<const CLI::ArgumentMismatch*>(&error) && !option.empty()) {
    const size_t received = what.find("received ");
    if (what.find("At Most") != std::string::npos && received != std::string::npos) {
      return option + " given " + what.substr(received + 9) + " times; give it once" + help;
    }
    if (what.find("required") != std::string::npos) return option + " needs a value" + help;
  }
  // a range check on a value that is not a number: "--episodes: Value x not in range 1 to 9"
  const size_t value_at = what.find(": Value ");
  const size_t range_at = what.find(" not in range ");
  if (dynamic_cast<const CLI::ValidationError*>(&error) && !option.empty() &&
      value_at == option.size() && range_at != std::string::npos) {
    const std::string value = what.substr(value_at + 8, range_at - value_at - 8);
    char* end = nullptr;
    std::strtod(value.c_str(), &end);
    const std::string kind = ValueKind(FindOption(command, option));
    const bool whole =
        !value.empty() && value.find_first_not_of("-+0123456789") == std::string::npos;
    // "2.5" is a number, but not the whole number an int option takes
    if (value.empty() || *end != '\0' || (kind == "a whole number" && !whole)) {
      return option + " needs " + kind + ", not '" + value + "'" + help;
    }
  }
  if (dynamic_cast<const CLI::ConversionError*>(&error) &&
      StartsWith(what, "Could not convert: ")) {
    // "Could not convert: --hud-opacity = abc"
    const std::string rest = what.substr(19);
    const size_t eq = rest.find(" = ");
    if (eq != std::string::npos) {
      const std::string name = rest.substr(0, eq), value = rest.substr(eq + 3);
      const std::string kind = ValueKind(FindOption(command, name));
      const bool digits = value.find_first_not_of("-0123456789") == std::string::npos;
      if (kind == "a whole number" && digits && !value.empty()) {
        return name + " " + value + " is out of range (too large a number)" + help;
      }
      return name + " needs " + kind + ", not '" + value + "'" + help;
    }
  }
  return what + help;
}

}  // namespace fetchscope::cli
