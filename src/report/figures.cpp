// gnuplot SVG figures of the report. Data files are decimated to a few thousand points per
// series: the figures show shape, the tables carry the numbers.
#include <fcntl.h>
#include <fmt/format.h>
#include <signal.h>
#include <spawn.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <optional>
#include <sstream>
#include <thread>
#include <vector>

#include "report_parts.hpp"
#include "thermodrift/error.hpp"
#include "thermodrift/io/atomic_file.hpp"

namespace thermodrift::report_detail {

namespace {

constexpr std::size_t kMaxPoints = 1500;
constexpr const char* kTerminal =
    "set terminal svg size 960,{} dynamic enhanced font 'Helvetica,12' background rgb 'white'\n";

std::size_t stride_for(std::size_t n) { return std::max<std::size_t>(1, (n + kMaxPoints - 1) / kMaxPoints); }

std::string quote(const std::string& text) {
  std::string out = "'";
  for (char c : text) out += (c == '\'') ? std::string("''") : std::string(1, c);
  return out + "'";
}

// `program` as the shell's `command -v` finds it: a name with a slash as given, else the
// first executable file of that name in $PATH.
std::optional<std::string> find_program(const std::string& program) {
  const auto executable = [](const std::string& path) {
    struct stat status {};
    return ::stat(path.c_str(), &status) == 0 && S_ISREG(status.st_mode) && ::access(path.c_str(), X_OK) == 0;
  };
  if (program.find('/') != std::string::npos) {
    return executable(program) ? std::optional<std::string>(program) : std::nullopt;
  }
  const char* path = std::getenv("PATH");
  std::istringstream folders(path ? path : "/usr/local/bin:/usr/bin:/bin");
  for (std::string folder; std::getline(folders, folder, ':');) {
    const std::string candidate = (std::filesystem::path(folder.empty() ? "." : folder) / program).string();
    if (executable(candidate)) return candidate;
  }
  return std::nullopt;
}

// Runs `program figures/figures.gp` in `dir`, its stdout and stderr to figures/gnuplot.log,
// and waits for it, asking `stop` every 10 ms: a stop request ends it (SIGTERM) and throws
// Interrupted. Not std::system, which ignores SIGINT in this process while the child runs:
// a Ctrl-C during the figures would be lost. Returns the exit status, -1 if it did not exit.
int run_gnuplot(const std::string& program, const std::string& dir, const StopToken& stop) {
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addchdir_np(&actions, dir.c_str());
  posix_spawn_file_actions_addopen(&actions, STDOUT_FILENO, "figures/gnuplot.log", O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_adddup2(&actions, STDOUT_FILENO, STDERR_FILENO);
  posix_spawnattr_t attributes;
  posix_spawnattr_init(&attributes);
  sigset_t defaults;  // the CLI ignores SIGPIPE; gnuplot gets the usual dispositions
  sigemptyset(&defaults);
  for (const int number : {SIGPIPE, SIGINT, SIGTERM}) sigaddset(&defaults, number);
  posix_spawnattr_setsigdefault(&attributes, &defaults);
  posix_spawnattr_setflags(&attributes, POSIX_SPAWN_SETSIGDEF);
  std::string script = "figures/figures.gp";
  std::vector<char*> argv{const_cast<char*>(program.c_str()), script.data(), nullptr};
  pid_t child = 0;
  const int spawned = ::posix_spawn(&child, program.c_str(), &actions, &attributes, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  posix_spawnattr_destroy(&attributes);
  if (spawned != 0) throw Error(fmt::format("cannot run {}: {}", program, std::strerror(spawned)));
  int raw = 0;
  for (;;) {
    const pid_t done = ::waitpid(child, &raw, WNOHANG);
    if (done == child) break;
    if (done < 0 && errno != EINTR) throw Error(fmt::format("waiting for {}: {}", program, std::strerror(errno)));
    if (stop.stop_requested()) {
      ::kill(child, SIGTERM);
      ::waitpid(child, &raw, 0);
      stop.throw_if_requested("figures");
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  return WIFEXITED(raw) ? WEXITSTATUS(raw) : -1;
}

// gnuplot's enhanced text treats _ ^ @ & { } as markup; in a single-quoted string one
// backslash escapes it (two print a backslash and leave the markup: "gyro\" and a
// subscript x).
std::string label(const std::string& text) {
  std::string out;
  for (char c : text) {
    if (c == '_' || c == '^' || c == '@' || c == '&' || c == '{' || c == '}') out += '\\';
    out += c;
  }
  return quote(out);
}

struct Script {
  std::ostringstream text;
  void begin(const std::string& file, int height) {
    text << fmt::format(kTerminal, height) << "set output " << quote(file) << "\n"
         << "reset session\nset grid\nset key outside right top\n";
  }
  void end() { text << "unset multiplot\nset output\n"; }
};

void split_marker(Script& script, double split_time) {
  script.text << fmt::format("set arrow 1 from {0:.6g}, graph 0 to {0:.6g}, graph 1 nohead dt 2 lc rgb 'gray40'\n",
                             split_time / 3600.0)
              << fmt::format("set label 1 'held out →' at {:.6g}, graph 0.95 offset 0.5,0 tc rgb 'gray40'\n",
                             split_time / 3600.0);
}

}  // namespace

std::string safe_file_name(const std::string& name) {
  std::string out;
  for (char c : name) out += std::isalnum(static_cast<unsigned char>(c)) ? c : '_';
  return out.empty() ? std::string("axis") : out;
}

FigureOutcome draw_figures(const FigureInputs& in, const std::string& dir, const std::string& gnuplot,
                           const StopToken& stop) {
  namespace fs = std::filesystem;
  FigureOutcome outcome;
  const auto program = find_program(gnuplot);
  if (!program) {
    outcome.note = fmt::format("'{}' is not installed, so the report has no figures (apt-get install gnuplot-nox)", gnuplot);
    return outcome;
  }
  const fs::path data_dir = fs::path(dir) / "figures";
  fs::create_directories(data_dir);
  const ChamberLog& log = *in.log;
  Script script;
  const auto data = [&](const std::string& name, const std::string& text) {
    stop.throw_if_requested("figures");
    write_file_atomically((data_dir / name).string(), text);
    return quote("figures/" + name);
  };

  // Raw output and temperatures.
  {
    std::ostringstream text;
    const auto stride = stride_for(log.rows());
    for (std::size_t r = 0; r < log.rows(); r += stride) {
      text << fmt::format("{:.6g}", log.time[r] / 3600.0);
      for (const auto& g : log.gyro) text << fmt::format(" {:.6g}", g[r]);
      for (const auto& t : log.temperature) text << fmt::format(" {:.6g}", t[r]);
      text << "\n";
    }
    const auto file = data("raw.dat", text.str());
    script.begin("raw.svg", 640);
    script.text << "set multiplot layout 2,1\nset xlabel 'time (h)'\nset ylabel 'gyro output (°/h)'\n";
    split_marker(script, in.split_time);
    script.text << "plot ";
    for (std::size_t a = 0; a < log.axes(); ++a) {
      script.text << (a ? ", " : "") << fmt::format("{} u 1:{} w l lw 1 t {}", file, a + 2, label(log.gyro_names[a]));
    }
    script.text << "\nset ylabel 'temperature (°C)'\nplot ";
    for (std::size_t c = 0; c < log.temperature.size(); ++c) {
      script.text << (c ? ", " : "")
                  << fmt::format("{} u 1:{} w l lw 1.5 t {}", file, log.axes() + c + 2, label(log.temperature_names[c]));
    }
    script.text << "\n";
    script.end();
    outcome.figures.push_back({"raw.svg", "Raw output and temperatures",
                               "Gyro output as logged (every " + std::to_string(stride) +
                                   "th sample) and the temperature channels; the dashed line is the start of the held-out part."});
  }

  // Smoothed drift (and the true drift when known).
  {
    std::ostringstream text;
    for (std::size_t a = 0; a < in.axes.size(); ++a) {
      const auto& axis = in.axes[a];
      const auto stride = stride_for(axis.time_s.size());
      for (std::size_t i = 0; i < axis.time_s.size(); i += stride) {
        text << fmt::format("{:.6g} {:.6g} {:.6g}\n", axis.time_s[i] / 3600.0, axis.smoothed[i],
                            axis.true_drift.empty() ? NAN : axis.true_drift[i]);
      }
      text << "\n\n";
    }
    const auto file = data("smoothed.dat", text.str());
    script.begin("smoothed.svg", 480);
    script.text << "set xlabel 'time (h)'\nset ylabel 'smoothed drift (°/h)'\n";
    split_marker(script, in.split_time);
    script.text << "plot ";
    for (std::size_t a = 0; a < in.axes.size(); ++a) {
      script.text << (a ? ", " : "") << fmt::format("{} i {} u 1:2 w l lw 1.5 lc {} t {}", file, a, a + 1,
                                                    label(in.axes[a].name + " smoothed"));
      if (!in.axes[a].true_drift.empty()) {
        script.text << fmt::format(", {} i {} u 1:3 w l dt 2 lc {} t {}", file, a, a + 1, label(in.axes[a].name + " true drift"));
      }
    }
    script.text << "\n";
    script.end();
    outcome.figures.push_back({"smoothed.svg", "Smoothed drift",
                               "Gyro output after the trailing moving average: the drift the models fit."
                               " Dashed: the true drift, when the log is simulated."});
  }

  // Fit and residual per axis.
  for (std::size_t a = 0; a < in.axes.size(); ++a) {
    const auto& axis = in.axes[a];
    const auto name = safe_file_name(axis.name);
    std::ostringstream text;
    const auto stride = stride_for(axis.time_s.size());
    for (std::size_t i = 0; i < axis.time_s.size(); i += stride) {
      text << fmt::format("{:.6g} {:.6g}", axis.time_s[i] / 3600.0, axis.smoothed[i]);
      for (const auto& p : axis.prediction) text << fmt::format(" {:.6g} {:.6g}", p[i], axis.smoothed[i] - p[i]);
      text << "\n";
    }
    const auto file = data("fit_" + name + ".dat", text.str());
    script.begin("fit_" + name + ".svg", 480);
    script.text << "set xlabel 'time (h)'\nset ylabel 'drift (°/h)'\n";
    split_marker(script, in.split_time);
    script.text << fmt::format("plot {} u 1:2 w l lw 3 lc rgb 'gray70' t 'smoothed drift'", file);
    for (std::size_t m = 0; m < axis.prediction.size(); ++m) {
      script.text << fmt::format(", {} u 1:{} w l lw 1.2 t {}", file, 3 + 2 * m, label(in.model_labels[m]));
    }
    script.text << "\n";
    script.end();
    outcome.figures.push_back({"fit_" + name + ".svg", "Model fit, " + axis.name,
                               "Each model's predicted drift over the smoothed drift, fitted left of the dashed line only."});

    script.begin("residual_" + name + ".svg", 480);
    script.text << "set xlabel 'time (h)'\nset ylabel 'residual after compensation (°/h)'\n";
    split_marker(script, in.split_time);
    script.text << "plot ";
    for (std::size_t m = 0; m < axis.prediction.size(); ++m) {
      script.text << (m ? ", " : "") << fmt::format("{} u 1:{} w l lw 1.2 t {}", file, 4 + 2 * m, label(in.model_labels[m]));
    }
    script.text << "\n";
    script.end();
    outcome.figures.push_back({"residual_" + name + ".svg", "Residual after compensation, " + axis.name,
                               "Smoothed drift minus each model's prediction."});
  }

  // Cross-axis experiment.
  const bool cross = std::any_of(in.axes.begin(), in.axes.end(), [](const AxisTrace& t) { return !t.cross_prediction.empty(); });
  if (cross) {
    std::ostringstream text;
    for (const auto& axis : in.axes) {
      const auto stride = stride_for(axis.time_s.size());
      const std::size_t svr = in.svr_index;
      for (std::size_t i = 0; i < axis.time_s.size(); i += stride) {
        text << fmt::format("{:.6g} {:.6g} {:.6g} {:.6g}\n", axis.time_s[i] / 3600.0, axis.smoothed[i],
                            axis.cross_prediction.empty() ? NAN : axis.cross_prediction[i],
                            axis.prediction.size() <= svr ? NAN : axis.prediction[svr][i]);
      }
      text << "\n\n";
    }
    const auto file = data("cross_axis.dat", text.str());
    script.begin("cross_axis.svg", 300 * static_cast<int>(in.axes.size()));
    script.text << fmt::format("set multiplot layout {},1\nset xlabel 'time (h)'\nset ylabel 'drift (°/h)'\n", in.axes.size());
    split_marker(script, in.split_time);
    for (std::size_t a = 0; a < in.axes.size(); ++a) {
      script.text << fmt::format("set title {}\n", label("left out: " + in.axes[a].name))
                  << fmt::format("plot {0} i {1} u 1:2 w l lw 3 lc rgb 'gray70' t 'smoothed drift', "
                                 "{0} i {1} u 1:3 w l lw 1.2 lc rgb 'red' t 'trained on the other axes', "
                                 "{0} i {1} u 1:4 w l lw 1.2 lc rgb 'blue' t {2}\n",
                                 file, a, label(in.model_labels.empty() ? "own axis" : in.model_labels[in.svr_index] + ", own axis"));
    }
    script.end();
    outcome.figures.push_back({"cross_axis.svg", "Cross-axis experiment (the paper's Fig. 3)",
                               "An SVR trained on the pooled samples of the other axes, tested on the axis left out,"
                               " beside that axis's own SVR."});
  }

  // Allan deviation.
  if (!in.allan.empty()) {
    std::ostringstream text;
    for (const auto& axis : in.allan) {
      for (const auto& curve : axis.curves) {
        for (const auto& p : curve.points) text << fmt::format("{:.6g} {:.6g}\n", p.tau_s, p.deviation);
        text << "\n\n";
      }
    }
    const auto file = data("allan.dat", text.str());
    const auto panels = in.allan.size();
    script.begin("allan.svg", 320 * static_cast<int>(panels));
    script.text << fmt::format("set multiplot layout {},1\nset logscale xy\nset format x '10^{{%L}}'\n"
                               "set format y '10^{{%L}}'\nset xlabel 'averaging time τ (s)'\n"
                               "set ylabel 'Allan deviation (°/h)'\n",
                               panels);
    std::size_t block = 0;
    for (const auto& axis : in.allan) {
      script.text << fmt::format("set title {}\nplot ", label(axis.name + ", held-out part"));
      for (std::size_t c = 0; c < axis.curves.size(); ++c) {
        script.text << (c ? ", " : "")
                    << fmt::format("{} i {} u 1:2 w lp pt 7 ps 0.4 lw {} t {}", file, block++, c == 0 ? 2.5 : 1.2,
                                   label(axis.curves[c].label));
      }
      script.text << "\n";
    }
    script.end();
    outcome.figures.push_back({"allan.svg", "Overlapping Allan deviation before and after compensation",
                               "On the held-out part: the raw output, and the output minus each model's predicted drift."});
  }

  // Tuning convergence.
  if (!in.tuning.empty()) {
    std::ostringstream text;
    for (const auto& history : in.tuning) {
      for (const auto& [evaluations, best] : history.points) text << fmt::format("{:.6g} {:.6g}\n", evaluations, best);
      text << "\n\n";
    }
    const auto file = data("tuning.dat", text.str());
    script.begin("tuning.svg", 480);
    script.text << "set logscale y\nset xlabel 'objective evaluations'\n"
                   "set ylabel 'best error so far (standardized MSE)'\nplot ";
    for (std::size_t h = 0; h < in.tuning.size(); ++h) {
      script.text << (h ? ", " : "") << fmt::format("{} i {} u 1:2 w steps lw 1.5 t {}", file, h, label(in.tuning[h].label));
    }
    script.text << "\n";
    script.end();
    outcome.figures.push_back({"tuning.svg", "Tuning convergence",
                               "Best objective value found against the number of evaluations."});
  }

  const std::string script_path = (data_dir / "figures.gp").string();
  write_file_atomically(script_path, script.text.str());
  const std::string log_path = (data_dir / "gnuplot.log").string();
  const int status = run_gnuplot(*program, dir, stop);
  if (status != 0) {
    throw Error(fmt::format("gnuplot failed (exit status {}) on {}; see {}", status, script_path, log_path));
  }
  for (const auto& figure : outcome.figures) {
    if (!fs::exists(fs::path(dir) / figure.file)) {
      throw Error(fmt::format("gnuplot did not write {}; see {}", figure.file, log_path));
    }
  }
  outcome.drawn = true;
  return outcome;
}

}  // namespace thermodrift::report_detail
