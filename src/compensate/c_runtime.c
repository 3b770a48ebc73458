/* The fixed part of an exported thermodrift header: the state, the feature pipeline
 * (FeatureStream::push, SmoothedChannel::push and TrailingMean::push, step for step) and
 * the filters of the feature terms (TermEvaluator, operation for operation).
 *
 * thermodrift export writes the model's configuration macros, then this file with its
 * prefixes tdrt_ and TDRT_ renamed to the header's own, then the model and the step
 * function. The configuration (each an integer constant unless said):
 *   TDRT_AXES, TDRT_TEMPERATURES, TDRT_MAX_RATE_HZ (double), TDRT_MEAN_CAPACITY,
 *   TDRT_HISTORY_CAPACITY, TDRT_FILTERS, TDRT_SINGLE_PRECISION (0 or 1), TDRT_RAW_INPUTS,
 *   TDRT_GRAD_CHANNELS (temperature channels per axis smoothed for grad terms),
 *   TDRT_RESUM_INITIAL (the trailing mean's first exact re-sum period),
 *   TDRT_RESUM_JUMP (a real: a value leaving the mean this many times larger than what
 *   stays forces a re-sum).
 * The tests compile this file on its own with each precision and with and without grad
 * channels (gcc -std=c99 -Wall -Wextra -Werror -pedantic). Internal to the export: edit
 * here, never in a generated header. */

#if !defined(TDRT_AXES) || !defined(TDRT_SINGLE_PRECISION) || !defined(TDRT_GRAD_CHANNELS)
#error "the configuration macros come first (see the comment above)"
#endif

#if TDRT_SINGLE_PRECISION
typedef float tdrt_real;
#define TDRT_EXP expf
#define TDRT_FABS fabsf
#else
typedef double tdrt_real;
#define TDRT_EXP exp
#define TDRT_FABS fabs
#endif

typedef struct {
  double time;
  tdrt_real value;
} tdrt_stamped;

/* One temperature channel of the feature pipeline: its trailing mean over
 * (t - smooth, t] and the history of that mean for the backward-difference rate. */
typedef struct {
  tdrt_stamped mean_ring[TDRT_MEAN_CAPACITY];
  unsigned long mean_head;
  unsigned long mean_count;
  unsigned long resum_period;        /* exact re-sum every this many pushes (mirrors the C++ ring) */
  unsigned long pushes_since_resum;
  tdrt_real mean_sum;
#if TDRT_SINGLE_PRECISION
  tdrt_real mean_carry;                /* Kahan compensation of mean_sum */
#endif
  tdrt_stamped history[TDRT_HISTORY_CAPACITY];
  unsigned long history_head;
  unsigned long history_count;
} tdrt_channel_state;

/* One axis: its own temperature channel, the channels its grad terms read, the lags. */
typedef struct {
  tdrt_channel_state temperature;
#if TDRT_GRAD_CHANNELS > 0
  tdrt_channel_state channel[TDRT_GRAD_CHANNELS];  /* read by grad terms */
#endif
  int started;
  double start_time;
  double last_time;
  double step_seconds;               /* since the previous sample; 0 at a (re)start */
  tdrt_real trend;                   /* a lag of the model's prediction (of the smoothed drift), for its slope */
  tdrt_real smoothed_drift;          /* the model's prediction at the previous sample */
  tdrt_real filters[TDRT_FILTERS][2];  /* lag states of the feature terms, two per factor */
} tdrt_axis_state;

typedef struct {
  tdrt_axis_state axis[TDRT_AXES];
  tdrt_real drift[TDRT_AXES];         /* last predicted drift per axis, deg/h */
  unsigned long dropped_samples;   /* ring overflows: the device sampled faster than TDRT_MAX_RATE_HZ */
  unsigned long rejected_samples;  /* samples with a non-finite or implausible input, rejected whole */
} tdrt_state;

typedef struct {
  double smooth_seconds;
  double rate_span_seconds;
  double gap_seconds;
  double warm_up_seconds;
  tdrt_real reference_temperature;
} tdrt_pipeline;

#if TDRT_SINGLE_PRECISION
/* Compensated (Kahan) summation: *sum + value with the rounding error carried.
 * Do not compile with -ffast-math, which would optimise the carry away. */
static inline void tdrt_accumulate(tdrt_real* sum, tdrt_real* carry, tdrt_real value) {
  const tdrt_real corrected = value - *carry;
  const tdrt_real total = *sum + corrected;
  *carry = (total - *sum) - corrected;
  *sum = total;
}
#endif

/* sum += value: in float compensated (Kahan), which keeps running sums within a few ulp
 * of the double result; in double a plain sum, operation for operation as in C++. */
#if TDRT_SINGLE_PRECISION
#define TDRT_ADD(sum, carry, value) tdrt_accumulate(&(sum), &(carry), (value))
#else
#define TDRT_ADD(sum, carry, value) ((sum) += (value))
#endif

static inline void tdrt_channel_restart(tdrt_channel_state* channel) {
  channel->mean_head = 0;
  channel->mean_count = 0;
  channel->mean_sum = 0;
#if TDRT_SINGLE_PRECISION
  channel->mean_carry = 0;
#endif
  channel->pushes_since_resum = 0;
  channel->history_head = 0;
  channel->history_count = 0;
}

static inline void tdrt_axis_restart(tdrt_axis_state* axis) {
  tdrt_channel_restart(&axis->temperature);
#if TDRT_GRAD_CHANNELS > 0
  {
    int c;
    for (c = 0; c < TDRT_GRAD_CHANNELS; ++c) tdrt_channel_restart(&axis->channel[c]);
  }
#endif
  axis->started = 0;
}

/* Resets every axis: call once before the first step (and to restart by hand). */
static inline void tdrt_init(tdrt_state* state) {
  int a;
  for (a = 0; a < TDRT_AXES; ++a) {
    tdrt_axis_restart(&state->axis[a]);
    state->axis[a].temperature.resum_period = TDRT_RESUM_INITIAL;
#if TDRT_GRAD_CHANNELS > 0
    {
      int c;
      for (c = 0; c < TDRT_GRAD_CHANNELS; ++c) state->axis[a].channel[c].resum_period = TDRT_RESUM_INITIAL;
    }
#endif
    state->axis[a].start_time = 0;
    state->axis[a].last_time = 0;
    state->axis[a].trend = 0;
    state->axis[a].smoothed_drift = 0;
    state->drift[a] = 0;
  }
  state->dropped_samples = 0;
  state->rejected_samples = 0;
}

/* Pushes one temperature into a channel; writes its mean and rate (degC/min).
 * Sets *dropped when a full ring had to lose its oldest sample. */
static inline void tdrt_channel_push(tdrt_channel_state* channel, const tdrt_pipeline* pipeline, double time,
                                    tdrt_real temperature, tdrt_real* smoothed, tdrt_real* rate, int* dropped) {
  double elapsed;
  const tdrt_stamped* past;
  tdrt_real leaving;
  int jump = 0;
  /* trailing mean over (t - smooth, t] */
  while (channel->mean_count > 0 && channel->mean_ring[channel->mean_head].time <= time - pipeline->smooth_seconds) {
    leaving = channel->mean_ring[channel->mean_head].value;
    TDRT_ADD(channel->mean_sum, channel->mean_carry, -leaving);
    channel->mean_head = (channel->mean_head + 1) % TDRT_MEAN_CAPACITY;
    --channel->mean_count;
    if (TDRT_FABS(leaving) > (tdrt_real)TDRT_RESUM_JUMP * (TDRT_FABS(channel->mean_sum) + (tdrt_real)channel->mean_count)) jump = 1;
  }
  if (channel->mean_count == channel->resum_period) channel->resum_period *= 2;
  if (channel->mean_count == TDRT_MEAN_CAPACITY) {
    leaving = channel->mean_ring[channel->mean_head].value;
    TDRT_ADD(channel->mean_sum, channel->mean_carry, -leaving);
    channel->mean_head = (channel->mean_head + 1) % TDRT_MEAN_CAPACITY;
    --channel->mean_count;
    if (TDRT_FABS(leaving) > (tdrt_real)TDRT_RESUM_JUMP * (TDRT_FABS(channel->mean_sum) + (tdrt_real)channel->mean_count)) jump = 1;
    *dropped = 1;
  }
  channel->mean_ring[(channel->mean_head + channel->mean_count) % TDRT_MEAN_CAPACITY].time = time;
  channel->mean_ring[(channel->mean_head + channel->mean_count) % TDRT_MEAN_CAPACITY].value = temperature;
  ++channel->mean_count;
  TDRT_ADD(channel->mean_sum, channel->mean_carry, temperature);
  /* a running sum drifts by rounding; re-adding the window once per period keeps it exact,
   * and at once when a value far larger than what stays has left (it took their digits) */
  if (++channel->pushes_since_resum >= channel->resum_period || jump) {
    unsigned long i;
    channel->mean_sum = 0;
#if TDRT_SINGLE_PRECISION
    channel->mean_carry = 0;
#endif
    for (i = 0; i < channel->mean_count; ++i) {
      TDRT_ADD(channel->mean_sum, channel->mean_carry, channel->mean_ring[(channel->mean_head + i) % TDRT_MEAN_CAPACITY].value);
    }
    channel->pushes_since_resum = 0;
  }
  *smoothed = channel->mean_sum / (tdrt_real)channel->mean_count;

  /* rate: backward difference to the last kept mean at or before t - span */
  if (channel->history_count == TDRT_HISTORY_CAPACITY) {
    channel->history_head = (channel->history_head + 1) % TDRT_HISTORY_CAPACITY;
    --channel->history_count;
    *dropped = 1;
  }
  channel->history[(channel->history_head + channel->history_count) % TDRT_HISTORY_CAPACITY].time = time;
  channel->history[(channel->history_head + channel->history_count) % TDRT_HISTORY_CAPACITY].value = *smoothed;
  ++channel->history_count;
  while (channel->history_count >= 2 &&
         channel->history[(channel->history_head + 1) % TDRT_HISTORY_CAPACITY].time <= time - pipeline->rate_span_seconds) {
    channel->history_head = (channel->history_head + 1) % TDRT_HISTORY_CAPACITY;
    --channel->history_count;
  }
  past = &channel->history[channel->history_head];
  elapsed = time - past->time;
  *rate = elapsed > 0 ? (*smoothed - past->value) / (tdrt_real)elapsed * (tdrt_real)60 : (tdrt_real)0;
}

/* Pushes the axis' own temperature (restarting after a gap); writes dT and the rate
 * (degC/min); returns 1 once warm. */
static inline int tdrt_axis_push(tdrt_axis_state* axis, const tdrt_pipeline* pipeline, double time,
                                 tdrt_real temperature, tdrt_real* delta_t, tdrt_real* rate, int* dropped) {
  tdrt_real smoothed;
  if (axis->started && (time - axis->last_time > pipeline->gap_seconds || !(time > axis->last_time))) {
    tdrt_axis_restart(axis);
  }
  axis->step_seconds = axis->started ? time - axis->last_time : 0;
  if (!axis->started) {
    axis->started = 1;
    axis->start_time = time;
  }
  axis->last_time = time;
  tdrt_channel_push(&axis->temperature, pipeline, time, temperature, &smoothed, rate, dropped);
#if TDRT_SINGLE_PRECISION
  *delta_t = smoothed;  /* the float rings hold T - reference */
#else
  *delta_t = smoothed - pipeline->reference_temperature;
#endif
  return time - axis->start_time >= pipeline->warm_up_seconds;
}

/* First-order lag, exact for an input held over the step; a step of 0 (a restart)
 * sets the state to the input: the lags start in equilibrium. */
static inline tdrt_real tdrt_lag(tdrt_real state, tdrt_real input, double step_seconds, double tau) {
  tdrt_real a;
  if (!(step_seconds > 0)) return input;
  a = (tdrt_real)TDRT_EXP((tdrt_real)(-step_seconds / tau));
  return a * state + ((tdrt_real)1 - a) * input;
}

/* max(0, value): the hinges of a piecewise-linear static map */
static inline tdrt_real tdrt_positive_part(tdrt_real value) {
  return value > 0 ? value : (tdrt_real)0;
}

/* lagrate:TAU, degC/min: the rate of a TAU-lag of dT (state[0]) */
static inline tdrt_real tdrt_lag_rate(tdrt_real* lagged, tdrt_real delta_t, double step_seconds, double tau) {
  *lagged = tdrt_lag(*lagged, delta_t, step_seconds, tau);
  return (tdrt_real)((delta_t - *lagged) / tau * 60.0);
}

/* lag2:T1:T2 (what 0), lag2rate:T1:T2 (1, degC/min) and nodehinge:T1:T2:TL:K (2): L1 = a
 * T1-lag of dT (state[0]), L2 a T2-lag of L1 (state[1]); the node N = L2 + TL dL2/dt, or
 * L1 + TL dL1/dt when T2 = 0, through max(0, N - K) */
static inline tdrt_real tdrt_node(tdrt_real state[2], tdrt_real delta_t, double step_seconds, double t1,
                                double t2, double tl, double knot, int what) {
  double node;
  state[0] = tdrt_lag(state[0], delta_t, step_seconds, t1);
  if (t2 > 0) state[1] = tdrt_lag(state[1], state[0], step_seconds, t2);
  if (what == 0) return state[1];
  if (what == 1) return (tdrt_real)((state[0] - state[1]) / t2 * 60.0);
  node = t2 > 0 ? state[1] + tl * (state[0] - state[1]) / t2 : state[0] + tl * (delta_t - state[0]) / t1;
  return node > knot ? (tdrt_real)(node - knot) : (tdrt_real)0;
}

/* play:TAU:W: (L - P)/W, L a TAU-lag of dT (state[0]), P (state[1]) the play operator on L
 * with half-width W: it moves only to stay within W of L; a restart sets it to L */
static inline tdrt_real tdrt_play(tdrt_real state[2], tdrt_real delta_t, double step_seconds, double tau,
                                tdrt_real width) {
  state[0] = tdrt_lag(state[0], delta_t, step_seconds, tau);
  if (!(step_seconds > 0)) state[1] = state[0];
  if (state[1] < state[0] - width) state[1] = state[0] - width;
  if (state[1] > state[0] + width) state[1] = state[0] + width;
  return (state[0] - state[1]) / width;
}

/* on:TAU: e^(-t/TAU), t the time since the (re)start (state[0]): 1 at power-on, then a
 * lag towards 0 */
static inline tdrt_real tdrt_turn_on(tdrt_real state[2], double step_seconds, double tau) {
  state[0] = step_seconds > 0 ? tdrt_lag(state[0], (tdrt_real)0, step_seconds, tau) : (tdrt_real)1;
  return state[0];
}

/* gradrate:TAU:TG, degC/min^2: the rate of a TG-lag (state[1]) of lagrate:TAU */
static inline tdrt_real tdrt_gradient_rate(tdrt_real state[2], tdrt_real delta_t, double step_seconds,
                                          double tau, double tau_gradient) {
  const tdrt_real coil_rate = tdrt_lag_rate(&state[0], delta_t, step_seconds, tau);
  state[1] = tdrt_lag(state[1], coil_rate, step_seconds, tau_gradient);
  return (tdrt_real)((coil_rate - state[1]) / tau_gradient * 60.0);
}

/* dir:TAU[:LAG[:R0]]: a TAU-lag (state[1]) of tanh(r / scale), scale = R0 degC/min, tanh
 * through exp; r is the smoothed rate, or lagrate:LAG when LAG > 0 */
static inline tdrt_real tdrt_direction(tdrt_real state[2], tdrt_real delta_t, tdrt_real rate,
                                     double step_seconds, double tau, double lag, double scale) {
  const double source = lag > 0 ? (double)tdrt_lag_rate(&state[0], delta_t, step_seconds, lag) : (double)rate;
  const double x = source / scale;
  state[1] = tdrt_lag(state[1], (tdrt_real)(1.0 - 2.0 / (exp(2.0 * x) + 1.0)), step_seconds, tau);
  return state[1];
}
