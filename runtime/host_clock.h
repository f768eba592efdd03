#pragma once

// This host's wall clock and name, as every shapesense program stamps its
// messages with them.
//
// On a rig the hosts' clocks are kept together by PTP and chrony
// (docs/rig.md), never perfectly: every age the programs compare across
// hosts is therefore taken from local receive times (header_t.data_age_us)
// or corrected by the measured offset (clock_offsets.h), never from one
// host's time minus another's. To prove that, the multi-host tests run each
// virtual host with its clock off by SHAPESENSE_TEST_CLOCK_OFFSET_MS, which
// every program reads through HostUtime.
#include <cstdint>
#include <string>

namespace shapesense {

// The environment variable of the test-only clock offset, ms (may be
// negative, fractional). Unset on a real rig.
inline constexpr const char* kTestClockOffsetVariable = "SHAPESENSE_TEST_CLOCK_OFFSET_MS";

// µs since the Unix epoch on this host's clock (plus the test offset).
int64_t HostUtime();
// The test offset HostUtime adds, µs (0 unless the variable is set). Throws
// std::invalid_argument naming the variable when it is not a number.
int64_t TestClockOffsetUs();

// This host's name (gethostname), "unknown" when it has none.
std::string HostName();

}  // namespace shapesense
