#pragma once

// One meaning for the exit codes of every shapesense program: 0 done,
// 1 failed, 2 bad input (a bad argument, config or file, named in the
// message). CLI11's own codes for parse errors (105-115) are folded into 2.
#include <CLI/CLI.hpp>
#include <optional>

namespace shapesense {

inline constexpr int kExitFailed = 1;
inline constexpr int kExitBadInput = 2;

// Parses the command line. nullopt: the program runs; otherwise it ends at
// once with this code (0 after --help, kExitBadInput after a parse error;
// CLI11 has printed either).
inline std::optional<int> ParseCommandLine(CLI::App& app, int argc, char** argv) {
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int code = app.exit(e);
    return code == 0 ? 0 : kExitBadInput;
  }
  return std::nullopt;
}

}  // namespace shapesense
