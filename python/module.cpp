// thermodrift._core: the C++ library under the Python package (python/thermodrift). The
// package's public API is in Python; this module hands it the command line's own pieces,
// so a keyword means what the option means, with the same checks and messages:
//   - options arrive as the CLI's arguments ("--gyro", "gx,gy") and are parsed by the
//     commands' own declarations (apps/thermodrift);
//   - logs arrive as NumPy arrays (no copy of a float64 column) and are checked as the
//     reader checks a file's cells;
//   - long calls run with the GIL released, on a worker thread, while this thread asks
//     Python every 0.1 s whether Ctrl-C was pressed (then the work's StopToken stops it and
//     KeyboardInterrupt is raised).
// Library errors become the package's exceptions (thermodrift.errors).
#include <pybind11/functional.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <fmt/format.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <mutex>
#include <optional>
#include <thread>

#include "commands.hpp"
#include "data_options.hpp"
#include "evaluate_command.hpp"
#include "fit_command.hpp"
#include "interrupt.hpp"
#include "thermodrift/compensate/compensator.hpp"
#include "thermodrift/error.hpp"
#include "thermodrift/models/model_file.hpp"
#include "thermodrift/report/allan.hpp"

namespace py = pybind11;

namespace thermodrift::python {

namespace {

using Column = py::array_t<double, py::array::c_style | py::array::forcecast>;

// Warnings of the library (cli::warn) collected during a call, raised as Python warnings
// once the call returns on the calling thread.
std::mutex warnings_mutex;
std::vector<std::string> pending_warnings;

void flush_warnings() {
  std::vector<std::string> messages;
  {
    std::lock_guard lock(warnings_mutex);
    messages.swap(pending_warnings);
  }
  if (messages.empty()) return;
  const py::object warn = py::module_::import("warnings").attr("warn");
  const py::object category = py::module_::import("thermodrift.errors").attr("ThermodriftWarning");
  // stacklevel 2: the caller of the package function (level 1 is the function itself).
  for (const auto& message : messages) warn(message, category, 2);
}

// Runs `work(stop)` on a worker thread with the GIL released; Ctrl-C stops it through
// the token and raises KeyboardInterrupt. The work's exception is rethrown here.
template <class Work>
auto run_interruptible(Work work) -> decltype(work(std::declval<const StopToken&>())) {
  using Result = decltype(work(std::declval<const StopToken&>()));
  std::atomic<bool> stop{false};
  std::optional<Result> result;
  std::exception_ptr error;
  bool interrupted = false;
  {
    py::gil_scoped_release release;
    std::mutex mutex;
    std::condition_variable finished;
    bool done = false;
    std::thread worker([&] {
      try {
        result.emplace(work(StopToken(stop)));
      } catch (...) {
        error = std::current_exception();
      }
      std::lock_guard lock(mutex);
      done = true;
      finished.notify_one();
    });
    std::unique_lock lock(mutex);
    while (!finished.wait_for(lock, std::chrono::milliseconds(100), [&] { return done; })) {
      lock.unlock();
      {
        py::gil_scoped_acquire gil;
        if (PyErr_CheckSignals() != 0) {
          PyErr_Clear();
          interrupted = true;
          stop = true;
          cli::set_interrupted(true);  // commands run through run_command read the CLI's flag
        }
      }
      lock.lock();
    }
    lock.unlock();
    worker.join();
  }
  cli::set_interrupted(false);
  flush_warnings();
  if (interrupted) {
    PyErr_SetNone(PyExc_KeyboardInterrupt);
    throw py::error_already_set();
  }
  if (error) std::rethrow_exception(error);
  return std::move(*result);
}

// A CLI::App with `declare`'s options, parsed from `arguments` (the CLI's spelling).
// Parse errors are UsageErrors worded as the tool words them.
template <class Declare>
std::unique_ptr<CLI::App> parsed(const std::vector<std::string>& arguments, Declare declare) {
  auto app = std::make_unique<CLI::App>("thermodrift");
  declare(*app);
  std::vector<std::string> reversed(arguments.rbegin(), arguments.rend());  // CLI11 pops from the back
  try {
    app->parse(reversed);
  } catch (const CLI::ParseError& e) {
    throw UsageError(e.what());
  }
  return app;
}

// One log handed over from Python as arrays, checked as the reader checks a file's cells.
struct Frame {
  std::string source;  // what error messages name ("DataFrame")
  Column time;
  std::vector<std::string> gyro_names;
  std::vector<Column> gyro;
  std::vector<std::string> temperature_names;
  std::vector<Column> temperature;
  std::vector<std::size_t> gyro_positions, temperature_positions;  // 1-based columns, for messages
  std::size_t time_position = 0;
};

ChamberLog to_log(const Frame& frame) {
  ChamberLog log;
  log.source = frame.source;
  const std::size_t rows = static_cast<std::size_t>(frame.time.size());
  if (rows == 0) throw DataError(frame.source, 0, 0, "no rows");
  const double* time = frame.time.data();
  const double start = time[0];
  log.time.resize(rows);
  log.line.resize(rows);
  for (std::size_t i = 0; i < rows; ++i) {
    if (!std::isfinite(time[i])) {
      throw DataError(frame.source, i + 1, frame.time_position, fmt::format("time is {}: not a finite number", time[i]));
    }
    if (i > 0 && !(time[i] > time[i - 1])) {
      throw DataError(frame.source, i + 1, frame.time_position,
                      fmt::format("time {:.17g} s is not after the previous row's {:.17g} s: times must increase",
                                  time[i], time[i - 1]));
    }
    log.time[i] = time[i] - start;  // seconds since the first row, as a file is read
    log.line[i] = i + 1;
  }
  auto copy = [&](const std::vector<Column>& columns, const std::vector<std::size_t>& positions, bool gyro) {
    std::vector<std::vector<double>> values;
    for (std::size_t c = 0; c < columns.size(); ++c) {
      if (static_cast<std::size_t>(columns[c].size()) != rows) {
        throw UsageError(fmt::format("{}: column {} has {} rows, the time {}", frame.source, positions[c],
                                     columns[c].size(), rows));
      }
      const double* data = columns[c].data();
      for (std::size_t i = 0; i < rows; ++i) {
        if (gyro ? plausible_rate(data[i]) : plausible_temperature(data[i])) continue;
        throw DataError(frame.source, i + 1, positions[c],
                        gyro ? fmt::format("gyro is {:.4g} °/h: not a finite number within ±{:.4g} °/h (10^5 °/s)",
                                           data[i], kMaxRateDph)
                             : fmt::format("temperature is {:.4g} °C: not a finite number within {} to {} °C",
                                           data[i], kMinTemperatureC, kMaxTemperatureC));
      }
      values.emplace_back(data, data + rows);
    }
    return values;
  };
  log.gyro = copy(frame.gyro, frame.gyro_positions, true);
  log.temperature = copy(frame.temperature, frame.temperature_positions, false);
  log.gyro_names = frame.gyro_names;
  log.temperature_names = frame.temperature_names;
  if (log.gyro.empty()) throw UsageError(fmt::format("{}: no gyro column", frame.source));
  if (log.temperature.empty()) throw UsageError(fmt::format("{}: no temperature column", frame.source));
  return log;
}

Frame frame_from(const py::dict& d) {
  Frame f;
  f.source = d["source"].cast<std::string>();
  f.time = d["time"].cast<Column>();
  f.time_position = d["time_position"].cast<std::size_t>();
  f.gyro_names = d["gyro_names"].cast<std::vector<std::string>>();
  f.gyro = d["gyro"].cast<std::vector<Column>>();
  f.gyro_positions = d["gyro_positions"].cast<std::vector<std::size_t>>();
  f.temperature_names = d["temperature_names"].cast<std::vector<std::string>>();
  f.temperature = d["temperature"].cast<std::vector<Column>>();
  f.temperature_positions = d["temperature_positions"].cast<std::vector<std::size_t>>();
  return f;
}

std::vector<ChamberLog> to_logs(const py::list& frames) {
  std::vector<ChamberLog> logs;
  for (const auto& item : frames) logs.push_back(to_log(frame_from(item.cast<py::dict>())));
  return logs;
}

// A NumPy array that takes over `values`' buffer (no copy); the array owns it.
py::array_t<double> to_array(std::vector<double>&& values) {
  auto* owned = new std::vector<double>(std::move(values));
  const py::capsule release(owned, [](void* p) { delete static_cast<std::vector<double>*>(p); });
  return py::array_t<double>(static_cast<py::ssize_t>(owned->size()), owned->data(), release);
}

py::object json_to_python(const nlohmann::json& json) {
  return py::module_::import("json").attr("loads")(json.dump());
}

// read_log: the CLI's data options (--data PATH ...) → the log's columns as arrays.
py::dict read_log(const std::vector<std::string>& arguments) {
  cli::DataOptions data;
  auto app = parsed(arguments, [&](CLI::App& a) { data.add_to(a); });
  if (data.files.size() != 1) throw UsageError("read_log reads one file");
  const LogSpec spec = data.spec();
  ChamberLog log = run_interruptible([&](const StopToken& stop) {
    return data.read(spec, data.warm_up_seconds(), stop).front();
  });
  py::dict out;
  out["source"] = log.source;
  out["time"] = to_array(std::move(log.time));
  out["time_origin"] = log.time_origin ? py::object(py::str(log.time_origin->text)) : py::object(py::none());
  out["gyro_names"] = log.gyro_names;
  py::list gyro, temperature;
  for (auto& column : log.gyro) gyro.append(to_array(std::move(column)));
  for (auto& column : log.temperature) temperature.append(to_array(std::move(column)));
  out["gyro"] = gyro;
  out["temperature_names"] = log.temperature_names;
  out["temperature"] = temperature;
  return out;
}

// A fitted or loaded model, with the sources it was fitted on (for save).
struct Model {
  DriftModel model;
  std::vector<std::string> sources;
  std::string path;  // file it was loaded from or last saved to
};

// fit: the CLI's fit options; the logs from the --data files or, when `frames` is not
// empty, from those arrays (`arguments` then carry how they were read, for the model's
// record). `progress(axis, axes, fraction, message)` is called from the worker thread.
std::pair<Model, py::object> fit(const std::vector<std::string>& arguments, const py::list& frames,
                                 const py::object& progress) {
  cli::FitArguments args;
  auto app = parsed(arguments, [&](CLI::App& a) { cli::add_fit_options(a, args, false); });
  if (frames.empty() && args.data.files.empty()) throw UsageError("no data: give a path or a DataFrame");
  std::vector<ChamberLog> logs = to_logs(frames);
  const LogSpec spec = args.data.format == "libsvm" ? LogSpec{} : args.data.spec();
  cli::FitProgress hooks;
  std::exception_ptr callback_error;
  bool stopped = false;  // the callback said stop: not called again (the axes run in parallel)
  if (!progress.is_none()) {
    auto call = [&](std::size_t axis, std::size_t axes, double fraction, const std::string& message) {
      py::gil_scoped_acquire gil;  // also guards callback_error and stopped
      if (callback_error || stopped) return false;
      try {
        const py::object keep_going = progress(axis, axes, fraction, message);
        stopped = !(keep_going.is_none() || keep_going.cast<bool>());
        return !stopped;
      } catch (...) {
        callback_error = std::current_exception();
        return false;
      }
    };
    hooks.tuning = [call](std::size_t axis, std::size_t axes, const optim::Progress& p) {
      return call(axis, axes, p.fraction_done,
                  fmt::format("tuning: iteration {}, {} evaluations, best {:.4g}", p.iteration, p.evaluations,
                              p.best_value));
    };
    hooks.step = [call](std::size_t axis, std::size_t axes, const std::string& what) { call(axis, axes, 0, what); };
  }
  cli::FitRun run;
  try {
    run = run_interruptible([&](const StopToken& stop) {
      return cli::fit_from_arguments(args, *app, std::move(logs), spec, stop, hooks);
    });
  } catch (const Interrupted&) {
    if (callback_error) std::rethrow_exception(callback_error);
    throw;
  }
  for (const auto& warning : cli::fit_run_warnings(run.calibration)) cli::warn(warning);
  flush_warnings();
  nlohmann::json axes = nlohmann::json::array();
  for (std::size_t a = 0; a < run.calibration.model.axes.size(); ++a) {
    nlohmann::json entry = run.calibration.axes[a].in_sample.to_json();
    entry["name"] = run.calibration.model.axes[a].name;
    entry["seconds"] = run.calibration.axes[a].seconds;
    entry["training_samples"] = run.calibration.axes[a].training_samples;
    axes.push_back(entry);
  }
  Model model{std::move(run.calibration.model), args.data.files, {}};
  for (const auto& frame : frames) {
    const std::string source = frame["file"].cast<std::string>();
    if (!source.empty()) model.sources.push_back(source);
  }
  return {std::move(model), json_to_python({{"evaluation", "in-sample"}, {"axes", axes}})};
}

// The drift and compensated rates of every row, through the field's Compensator, and the
// compensate command's flags (1 not ready, 2 outside the training envelope).
py::tuple compensate(const Model& m, const py::dict& frame_dict, bool shared_temperature) {
  const Frame frame = frame_from(frame_dict);
  const std::size_t rows = static_cast<std::size_t>(frame.time.size());
  const std::size_t axes = m.model.axes.size();
  const std::size_t inputs = m.model.temperature_inputs();
  if (frame.gyro.size() != axes) {
    throw UsageError(fmt::format("the model has {} axes but {} gyro columns were given", axes, frame.gyro.size()));
  }
  if (!(shared_temperature ? frame.temperature.size() == 1 : frame.temperature.size() == inputs)) {
    throw UsageError(fmt::format("the model reads {} temperature inputs; {} columns were given", inputs,
                                 frame.temperature.size()));
  }
  for (const auto& column : frame.gyro) {
    if (static_cast<std::size_t>(column.size()) != rows) throw UsageError("the columns differ in length");
  }
  for (const auto& column : frame.temperature) {
    if (static_cast<std::size_t>(column.size()) != rows) throw UsageError("the columns differ in length");
  }
  py::array_t<double> drift({rows, axes});
  py::array_t<double> compensated({rows, axes});
  py::array_t<std::int8_t> flags({rows, axes});
  double* drift_out = drift.mutable_data();
  double* compensated_out = compensated.mutable_data();
  std::int8_t* flags_out = flags.mutable_data();
  std::vector<const double*> gyro, temperature;
  for (const auto& column : frame.gyro) gyro.push_back(column.data());
  for (const auto& column : frame.temperature) temperature.push_back(column.data());
  const double* time = frame.time.data();
  const DriftModel& model = m.model;
  run_interruptible([&](const StopToken& stop) {
    Compensator compensator(model);
    std::vector<double> rates(axes), temperatures(inputs);
    const double start = rows > 0 ? time[0] : 0;
    for (std::size_t i = 0; i < rows; ++i) {
      if ((i & 0xFFFF) == 0) stop.throw_if_requested("compensation");
      if (i > 0 && !(time[i] > time[i - 1])) {
        throw DataError(frame.source, i + 1, frame.time_position, "times must increase");
      }
      for (std::size_t a = 0; a < axes; ++a) rates[a] = gyro[a][i];
      for (std::size_t c = 0; c < inputs; ++c) temperatures[c] = temperature[shared_temperature ? 0 : c][i];
      const auto& out = compensator.push(time[i] - start, rates, temperatures);
      for (std::size_t a = 0; a < axes; ++a) {
        drift_out[i * axes + a] = out.drift[a];
        compensated_out[i * axes + a] = out.compensated[a];
        const auto& status = out.axes[a];
        flags_out[i * axes + a] = static_cast<std::int8_t>((status.ready ? 0 : 1) | (status.outside_envelope.any() ? 2 : 0));
      }
    }
    return 0;
  });
  return py::make_tuple(drift, compensated, flags);
}

// Runs one subcommand as the tool would (its options, checks and output), for the
// commands whose product is a file (simulate, report, export, compress).
int run_command(const std::vector<std::string>& arguments) {
  CLI::App app{"thermodrift"};
  app.require_subcommand(1);
  const auto commands = cli::register_commands(app);
  std::vector<std::string> reversed(arguments.rbegin(), arguments.rend());
  try {
    app.parse(reversed);
  } catch (const CLI::ParseError& e) {
    throw UsageError(e.what());
  }
  return run_interruptible([&](const StopToken&) { return cli::run_selected(commands); });
}

// The keywords a call takes: the long names of the command's options, as Python spells
// them ("rate_span"), for "fit" and "read_log" (the data options).
std::vector<std::string> keywords(const std::string& command) {
  CLI::App app;
  cli::FitArguments args;
  if (command == "fit") {
    cli::add_fit_options(app, args, false);
  } else if (command == "read_log") {
    args.data.add_to(app);
  } else {
    throw UsageError(fmt::format("no keywords for {}", command));
  }
  std::vector<std::string> names;
  for (const CLI::Option* option : app.get_options()) {
    for (std::string name : option->get_lnames()) {
      std::replace(name.begin(), name.end(), '-', '_');
      if (name != "help") names.push_back(name);
    }
  }
  return names;
}

// A property of the model: `of(axis)` for every axis, in order.
template <class Of>
auto per_axis(Of of) {
  return [of](const Model& self) {
    std::vector<decltype(of(self.model.axes.front()))> values;
    for (const auto& axis : self.model.axes) values.push_back(of(axis));
    return values;
  };
}

void translate(std::exception_ptr error) {
  if (!error) return;
  const py::module_ errors = py::module_::import("thermodrift.errors");
  try {
    std::rethrow_exception(error);
  } catch (const Interrupted&) {
    PyErr_SetNone(PyExc_KeyboardInterrupt);
  } catch (const DataError& e) {
    const py::object exception =
        errors.attr("DataError")(e.what(), py::arg("file") = e.file(), py::arg("line") = e.line(),
                                 py::arg("column") = e.column());
    PyErr_SetObject(errors.attr("DataError").ptr(), exception.ptr());
  } catch (const UsageError& e) {
    PyErr_SetString(errors.attr("UsageError").ptr(), e.what());
  } catch (const Error& e) {
    PyErr_SetString(errors.attr("ThermodriftError").ptr(), e.what());
  }
}

}  // namespace

}  // namespace thermodrift::python

PYBIND11_MODULE(_core, m) {
  using namespace thermodrift;
  using namespace thermodrift::python;
  m.doc() = "thermodrift's C++ core; use the thermodrift package";
  py::register_exception_translator(&translate);
  cli::set_warning_sink([](const std::string& message) {
    std::lock_guard lock(warnings_mutex);
    pending_warnings.push_back(message);
  });

  py::class_<Model>(m, "Model")
      .def_static("load",
                  [](const std::string& path) {
                    Model model{load_drift_model(path), {}, path};
                    return model;
                  })
      .def("save",
           [](Model& self, const std::string& path) {
             save_drift_model(self.model, path, self.sources);
             self.path = path;
           })
      .def_property_readonly("path", [](const Model& self) { return self.path; })
      .def("to_json", [](const Model& self) { return json_to_python(to_json(self.model)); })
      .def_property_readonly("axes", per_axis([](const AxisModel& axis) { return axis.name; }))
      .def_property_readonly("terms", per_axis([](const AxisModel& axis) { return axis.pipeline.term_names(); }))
      .def_property_readonly("params", per_axis([](const AxisModel& axis) {
                               return json_to_python(axis.fit.params ? to_json(*axis.fit.params) : nlohmann::json::object());
                             }))
      .def_property_readonly("kinds", per_axis([](const AxisModel& axis) { return std::string(to_string(axis.kind)); }))
      .def_property_readonly("gyro_columns", per_axis([](const AxisModel& axis) { return axis.gyro_column; }))
      .def_property_readonly("temperature_columns",
                             [](const Model& self) {
                               std::vector<std::string> columns;
                               for (const auto& axis : self.model.axes) columns.push_back(axis.temperature_column);
                               for (const auto& extra : self.model.extra_temperature_columns) columns.push_back(extra);
                               return columns;
                             })
      .def_property_readonly("time_column",
                             [](const Model& self) { return self.model.time_column.value_or(std::string()); })
      .def("compensate", &compensate)
      .def("evaluate", [](const Model& self, const py::list& frames, double settle, const std::string& start) {
        std::vector<ChamberLog> logs = to_logs(frames);
        const LogStart log_start = parse_log_start(start);
        const nlohmann::json result = run_interruptible([&](const StopToken& stop) {
          return cli::evaluation_result(self.model, self.path, logs, settle, stop, log_start);
        });
        return json_to_python(result);
      });
  m.def("read_log", &read_log, "the CLI's data options, --data PATH among them");
  m.def("fit", &fit);
  m.def("run_command", &run_command, "runs a subcommand as the tool does");
  m.def(
      "allan_deviation",
      [](const Column& rate, double sample_rate_hz, int points_per_decade, double max_tau_fraction) {
        const auto points = overlapping_allan_deviation(std::span<const double>(rate.data(), rate.size()),
                                                        sample_rate_hz, points_per_decade, max_tau_fraction);
        std::vector<double> tau, deviation;
        std::vector<std::size_t> terms;
        for (const auto& point : points) {
          tau.push_back(point.tau_s);
          deviation.push_back(point.deviation);
          terms.push_back(point.terms);
        }
        return py::make_tuple(to_array(std::move(tau)), to_array(std::move(deviation)), terms);
      },
      "overlapping Allan deviation (report/allan.hpp)");
  m.def("keywords", &keywords, "the keywords of fit or read_log (their options' long names)");
}
