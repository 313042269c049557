// The host programs' command lines (CLI11, Debian's libcli11-dev): one way to end a parse, so that
// every program answers --help and a bad flag alike.
#pragma once

#include <CLI/CLI.hpp>
#include <cstdio>
#include <functional>
#include <string>

namespace sim {

/// Parses argv into `app`. Returns -1 to go on, else the exit status to end with: 0 after printing
/// the help (--help), 2 after printing "NAME: what is wrong" and where to look on stderr. `what`
/// may name the error better than CLI11 does (it gets CLI11's error and returns the message).
inline int parse_command_line(CLI::App& app, int argc, char** argv, const char* name, const char* lists = "the options",
                              const std::function<std::string(const CLI::ParseError&)>& what = {}) {
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp&) {
    std::printf("%s", app.help().c_str());
    return 0;
  } catch (const CLI::ParseError& e) {
    const std::string message = what ? what(e) : std::string(e.what());
    std::fprintf(stderr, "%s: %s\n(%s --help lists %s)\n", name, message.c_str(), name, lists);
    return 2;
  }
  return -1;
}

}  // namespace sim
