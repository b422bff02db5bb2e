#pragma once
// Time since the process started, for a time split that adds up to what the user waited: the
// executable's own start-up (the dynamic loader mapping and relocating its libraries, static
// initialisation) happens before main() and no stopwatch of the program can see it.
namespace candela {

/// Seconds from the start of this process to now, on the monotonic clock. The start is the
/// kernel's record of it (/proc/self/stat, field 22, in clock ticks since boot; the middle of
/// that tick is taken, so it is within half a tick, 5 ms at the usual 100 ticks a second), never
/// later than the static initialisation of this program; where /proc cannot be read, that
/// initialisation is the start.
double process_seconds();

} // namespace candela
