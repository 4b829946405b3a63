// One line for each way a command line fails to parse (CLI11's ParseError): the option it is
// about, a "did you mean" for a near miss, and the help of the subcommand actually used.
#pragma once

#include <CLI/CLI.hpp>
#include <string>

namespace fetchscope::cli {

/// The message (without "fetchscope: error: ") for `error`, thrown by `app.parse(argc, argv)`:
/// an unknown command or option with the nearest known name, an option given twice, without a
/// value or with one of the wrong type, each naming the option and "see fetchscope CMD --help".
std::string ParseErrorMessage(const CLI::App& app, const CLI::ParseError& error, int argc,
                              const char* const* argv);

}  // namespace fetchscope::cli
