// The model file: one JSON document per fit, holding for every gyro axis the columns it
// reads, the feature pipeline, and the fitted model. Versioned; loading checks
// everything and rejects a file that does not fit with a one-line DataError.
#pragma once

#include <nlohmann/json.hpp>

#include <optional>
#include <span>
#include <string>
#include <variant>
#include <vector>

#include "thermodrift/features/envelope.hpp"
#include "thermodrift/features/pipeline.hpp"
#include "thermodrift/io/chamber_log.hpp"
#include "thermodrift/models/fit_record.hpp"
#include "thermodrift/models/linear.hpp"
#include "thermodrift/models/model_kind.hpp"
#include "thermodrift/models/svr_model.hpp"

namespace thermodrift {

class AtomicFile;

struct AxisModel {
  std::string name;                // axis label, the gyro column's header name or "column N"
  std::string gyro_column;         // as named to the reader: header name or 1-based index
  std::string temperature_column;  // likewise
  Pipeline pipeline;
  ModelKind kind = ModelKind::linear;
  std::variant<LinearModel, SvrModel> model;
  FitRecord fit;                   // how it was fitted: what was tuned, how, with what result (informational)
  // What the training logs covered (features/envelope.hpp); absent in files written
  // before it was recorded and for libsvm-format models.
  std::optional<TrainingEnvelope> envelope;

  // Predicted drift (°/h) for one sample's features (one per pipeline term).
  double predict(std::span<const double> features) const;
  Eigen::VectorXd predict(const Eigen::MatrixXd& features) const;
};

struct DriftModel {
  static constexpr int kFormatVersion = 1;
  GyroUnit gyro_unit = GyroUnit::dph;     // unit of the gyro columns the model reads
  std::optional<std::string> time_column;  // as in the training log's LogSpec
  TimeUnit time_unit = TimeUnit::s;        // of the numbers in that column
  // Raw values to °C and °/h as the training log was read: each list empty (default),
  // one value for all, or one per axis (gyro) / per temperature input (temperature).
  LogScaling scaling;
  // The spike filter the training logs were read with (evaluate and compensate read with
  // it too), and how many samples it replaced there: per axis' gyro, per temperature input.
  std::optional<DespikeOptions> despike;
  std::vector<std::size_t> despiked_gyro, despiked_temperature;
  std::optional<double> rate_hz;
  std::vector<AxisModel> axes;
  // Temperature columns after the axes' own, read only by grad terms (as named to the
  // reader). The model's temperature inputs are the axes' columns, then these: channel
  // numbers of grad terms count in that order, as in the training log's --temp list.
  std::vector<std::string> extra_temperature_columns;

  // The LogSpec that reads a log the way the training log was read.
  LogSpec log_spec() const;
  // Temperature inputs a sample needs: one per axis, then the extra channels.
  std::size_t temperature_inputs() const { return axes.size() + extra_temperature_columns.size(); }
};

nlohmann::json to_json(const DriftModel& model);
class JsonPositions;
// Throws DataError(source, ...) on anything that does not fit; with the positions of the
// text `json` was parsed from, at the line and column of the value refused.
DriftModel drift_model_from_json(const nlohmann::json& json, const std::string& source,
                                 const JsonPositions* positions = nullptr);

void save_drift_model(const DriftModel& model, const std::string& path,
                      const std::vector<std::string>& inputs = {});
// The same into an output opened earlier (a FIFO's reader then gets an end of file when
// the work before the save fails); commits it.
void save_drift_model(const DriftModel& model, AtomicFile& out);
DriftModel load_drift_model(const std::string& path);

}  // namespace thermodrift
