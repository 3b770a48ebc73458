/* Any stream of samples through the exported C header's step function, as the
 * compensator fuzz target does for the C++ Compensator: times that repeat, go back, jump
 * by hours or come faster than the rings are sized for; NaN, infinities, values at and
 * beyond the physical ranges. step must never return 1 with a non-finite output, never
 * touch memory outside its state (the sanitizers watch), and count every implausible
 * sample in rejected_samples.
 *
 * The headers are exported at build time (tests/fuzz/CMakeLists.txt) from models fitted
 * on a simulated log: a linear model on lag, hinge, play, memory and Shupe terms in
 * double and in float, and the paper's SVR reduced to 16 vectors per axis (so a run is
 * quick), rings sized for 1 Hz.
 * Input: byte 0 picks the header; then records of 7 bytes: a time step code, a gyro code
 * per axis (3), a temperature code per axis (3). */
#include <math.h>
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>

#include "fuzz_linear.h"
#include "fuzz_float.h"
#include "fuzz_svr.h"

#define MAX_RATE_DPH 3.6e8
#define MIN_TEMPERATURE_C (-273.15)
#define MAX_TEMPERATURE_C 1000.0

/* A value from a code: mostly plausible readings around `centre`, else a special value. */
static double value(uint8_t code, double centre, double step, double high, double low) {
  switch (code) {
    case 0: return NAN;
    case 1: return INFINITY;
    case 2: return -INFINITY;
    case 3: return 1e300;
    case 4: return -1e300;
    case 5: return high; /* at the edge of the range: a reading */
    case 6: return low;
    case 7: return nextafter(high, INFINITY); /* just beyond it: rejected */
    case 8: return nextafter(low, -INFINITY);
    case 9: return 4.9406564584124654e-324; /* the smallest subnormal */
    default: return centre + step * ((double)code - 128.0);
  }
}

static double time_step(uint8_t code) {
  switch (code) {
    case 0: return 0;    /* a repeated stamp */
    case 1: return -1;   /* the clock went back */
    case 2: return 3600; /* a gap of an hour */
    case 3: return 1e-9; /* faster than the rings are sized for */
    case 4: return 1e9;
    default: return 0.1 * (double)(code % 20) + 0.05;
  }
}

/* One header's run over the records; each header has its own prefix, so one macro
 * serves the three. */
#define RUN(P, AXES, TEMPERATURES)                                                              \
  do {                                                                                          \
    P##_state state;                                                                            \
    double time = 0;                                                                            \
    unsigned long implausible = 0;                                                              \
    size_t at;                                                                                  \
    P##_init(&state);                                                                           \
    for (at = 1; at + 7 <= size; at += 7) {                                                     \
      double gyro[AXES], temperature[TEMPERATURES], compensated[AXES];                          \
      const double stamp = data[at] == 5 ? NAN : (time += time_step(data[at]));                 \
      int plausible = isfinite(stamp);                                                          \
      int k, ready;                                                                             \
      for (k = 0; k < AXES; ++k) {                                                              \
        gyro[k] = value(data[at + 1 + k % 3], 5.0, 0.5, MAX_RATE_DPH, -MAX_RATE_DPH);          \
        plausible = plausible && gyro[k] >= -MAX_RATE_DPH && gyro[k] <= MAX_RATE_DPH;           \
      }                                                                                         \
      for (k = 0; k < TEMPERATURES; ++k) {                                                      \
        temperature[k] = value(data[at + 4 + k % 3], 20.0, 0.4, MAX_TEMPERATURE_C, MIN_TEMPERATURE_C); \
        plausible = plausible && temperature[k] >= MIN_TEMPERATURE_C && temperature[k] <= MAX_TEMPERATURE_C; \
      }                                                                                         \
      implausible += !plausible;                                                                \
      ready = P##_step(&state, stamp, gyro, temperature, compensated);                          \
      if (ready && !plausible) abort();                                                         \
      for (k = 0; k < AXES; ++k) {                                                              \
        if (ready && !isfinite(compensated[k])) abort(); /* a non-finite value flagged valid */ \
      }                                                                                         \
    }                                                                                           \
    if (state.rejected_samples != implausible) abort();                                         \
  } while (0)

int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 1) return 0;
  switch (data[0] % 3) {
    case 0: RUN(fuzz_linear, FUZZ_LINEAR_AXES, FUZZ_LINEAR_TEMPERATURES); break;
    case 1: RUN(fuzz_float, FUZZ_FLOAT_AXES, FUZZ_FLOAT_TEMPERATURES); break;
    default: RUN(fuzz_svr, FUZZ_SVR_AXES, FUZZ_SVR_TEMPERATURES); break;
  }
  return 0;
}
