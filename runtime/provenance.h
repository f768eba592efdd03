#pragma once

// What produced a result: the project's version (git describe at build
// time, "-dirty" for uncommitted changes) and when, written next to results
// so that a number in a paper can be traced to the code and the options.
#include <filesystem>
#include <string>

namespace shapesense {

// "v0.1-42-gabc1234", "abc1234-dirty", or "0.1.0 (not a git checkout)".
std::string ProjectVersion();

// The current time, UTC, as 2026-11-26T03:04:05Z.
std::string UtcNow();

// Writes `path` (atomically): the effective options as a config file that
// `--config` takes back as it is, headed by comments naming the version,
// the time and `what` ("shapesense offline on DATASET -> OUT").
void WriteEffectiveConfig(const std::filesystem::path& path, const std::string& what,
                          const std::string& options_yaml);

}  // namespace shapesense
