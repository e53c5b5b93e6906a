#pragma once
// The exit-code contract of every hystloop program, for its command line:
//   0  ok (also --help / --help-all / --version: printed, nothing run)
//   1  runtime failure
//   2  usage error or refused input
// CLI11's own codes (105 for a failed check, 106 for an extra argument, ...) and its
// CLI11_PARSE macro are not used: parse_cli maps every parse error to 2, with the message on
// stderr as "<program>: <message>". Use:
//   if (const auto exit_code = hystloop::parse_cli(app, argc, argv)) return *exit_code;
// Tested for every program by tests/integration/exit_codes.sh.

#include <CLI/CLI.hpp>

#include <cstdio>
#include <exception>
#include <filesystem>
#include <map>
#include <optional>
#include <string>

#include "core/errors.hpp"

namespace hystloop {

inline constexpr int kExitOk = 0;
inline constexpr int kExitFailure = 1;
inline constexpr int kExitUsage = 2;

// An option naming an axis of an XY(Z) stage as x, y or z, stored as 0, 1 or 2 (anything else is
// refused by the parser, naming the choices).
inline CLI::Option* add_axis_option(CLI::App* app, const std::string& name, int& axis, const std::string& help) {
  return app->add_option(name, axis, help)
      ->transform(CLI::CheckedTransformer(std::map<std::string, int>{{"x", 0}, {"y", 1}, {"z", 2}}).description(""))
      ->type_name("x|y|z");
}

// nullopt: parsed, go on; otherwise the code to exit with.
inline std::optional<int> parse_cli(CLI::App& app, int argc, const char* const* argv) {
  try {
    app.parse(argc, argv);
  } catch (const CLI::Success& e) {  // --help, --help-all, --version
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    const std::string program = std::filesystem::path(argc > 0 ? argv[0] : app.get_name()).filename().string();
    // A word where a command was expected is an unknown command, whatever CLI11 makes of it
    // ("A subcommand is required", or an extra argument): name it and the commands there are.
    const auto commands = app.get_subcommands([](const CLI::App*) { return true; });
    if (app.get_require_subcommand_min() > 0 && !commands.empty() && app.get_subcommands().empty() && argc > 1 &&
        argv[1][0] != '-') {
      std::string names;
      for (const CLI::App* c : commands) names += (names.empty() ? "" : ", ") + c->get_name();
      std::fprintf(stderr, "%s: unknown command '%s' (one of: %s)\nRun with --help for more information.\n",
                   program.c_str(), argv[1], names.c_str());
      return kExitUsage;
    }
    std::fprintf(stderr, "%s: %s\nRun with --help for more information.\n", program.c_str(), e.what());
    return kExitUsage;
  }
  return std::nullopt;
}

// The last guard of every main, called from its final catch (...): what no other handler took
// (CLI11's own set-up, a bug) is printed as "<program>: <what>" and the program exits 1.
inline int exit_on_escaped_exception(const char* program) noexcept {
  try {
    throw;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "%s: %s\n", program, e.what());
  } catch (...) {
    std::fprintf(stderr, "%s: unknown error\n", program);
  }
  return kExitFailure;
}

// A tool's whole main: run() parses its command line and does the work; what it throws keeps
// the contract above, printed as "<program>: <what>": a ParameterError (refused input) exits 2,
// anything else 1.
template <class Run>
int run_tool(const char* program, Run&& run) noexcept {
  try {
    return run();
  } catch (const ParameterError& e) {
    std::fprintf(stderr, "%s: %s\n", program, e.what());
    return kExitUsage;
  } catch (...) {
    return exit_on_escaped_exception(program);
  }
}

}  // namespace hystloop
