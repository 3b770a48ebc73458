/* firmware_loop.c: a navigation computer's 1 Hz loop compensating gyro drift with a
 * header written by `thermodrift export` (see examples/README.md for how to make it).
 *
 * A real loop reads the gyro and the temperature sensors; here they are stand-ins that
 * play a chamber heating at 1 degC/min from 20 degC with a gyro whose output is a
 * constant 15 deg/h rotation plus a drift that follows temperature. The loop steps the
 * compensator, uses the compensated rates once it is ready, and shows what happens at a
 * gap in the samples (a sensor bus stalled for 5 minutes).
 *
 *   gcc -std=c99 -Wall -Wextra -pedantic -O2 -I. firmware_loop.c -o firmware_loop -lm
 *   ./firmware_loop
 *
 * With the header of examples/README.md (a linear model fitted on one simulated cycle),
 * it prints:
 *
 *   t=   0 s  T=20.00 degC  raw x= 15.500 deg/h  compensated x= 14.543 deg/h  (warm-up)
 *   t= 200 s: ready, using compensated rates
 *   t= 300 s  T=25.00 degC  raw x= 15.650 deg/h  compensated x= 13.307 deg/h
 *   t= 600 s  T=30.00 degC  raw x= 15.800 deg/h  compensated x= 13.331 deg/h
 *   t= 900 s: warming up, using raw rates
 *   t= 900 s  T=35.00 degC  raw x= 15.950 deg/h  compensated x= 14.616 deg/h  (warm-up)
 *   t=1100 s: ready, using compensated rates
 *   t=1200 s  T=40.00 degC  raw x= 16.100 deg/h  compensated x= 13.379 deg/h
 *   dropped samples: 0
 *
 * Ready after 200 s (100 s smoothing + 100 s rate span), again 200 s after the gap. The
 * compensated rate is not 15 deg/h because the stand-in's made-up drift law is not the
 * one the model learnt from the simulated chamber (whose drift also follows dT/dt at
 * ~1.2-3 deg/h per degC/min); with the real gyro it removes the real drift.
 */
#include <stdio.h>

#include "thermodrift_model.h"

/* The compensator's state: ring buffers sized at export time for --max-rate. It is
 * large (10 kB at 1 Hz, about 1 MB at 100 Hz), so it is static, never on the stack. */
static thermodrift_state compensator;

/* Stand-in sensors: time t in s. */
static double chamber_temperature(double t) { return 20.0 + t / 60.0; }
/* temperature_c: one per axis, then any extra channel the model's grad terms read. */
static void read_sensors(double t, double gyro_dph[THERMODRIFT_AXES], double temperature_c[THERMODRIFT_TEMPERATURES]) {
  int a;
  for (a = 0; a < THERMODRIFT_TEMPERATURES; ++a) temperature_c[a] = chamber_temperature(t);
  for (a = 0; a < THERMODRIFT_AXES; ++a) {
    gyro_dph[a] = 15.0 + 0.5 + 0.03 * (temperature_c[a] - 20.0); /* true rate + drift */
  }
}

int main(void) {
  double gyro[THERMODRIFT_AXES];
  double temperature[THERMODRIFT_TEMPERATURES];
  double compensated[THERMODRIFT_AXES];
  double t;
  int was_ready = 0;
  thermodrift_init(&compensator);
  for (t = 0; t <= 1200; t += 1.0) {
    int ready;
    if (t > 600 && t < 900) continue; /* bus stall: no samples for 5 minutes */
    read_sensors(t, gyro, temperature);
    ready = thermodrift_step(&compensator, t, gyro, temperature, compensated);
    if (ready != was_ready) {
      printf("t=%4.0f s: %s\n", t, ready ? "ready, using compensated rates" : "warming up, using raw rates");
      was_ready = ready;
    }
    /* The attitude filter would take compensated[] when ready, else gyro[] with a
     * larger noise figure. Print one line every 5 minutes for the x axis. */
    if ((long)t % 300 == 0) {
      printf("t=%4.0f s  T=%5.2f degC  raw x=%7.3f deg/h  compensated x=%7.3f deg/h  %s\n", t, temperature[0],
             gyro[0], compensated[0], ready ? "" : "(warm-up)");
    }
  }
  printf("dropped samples: %lu\n", compensator.dropped_samples);
  return 0;
}
