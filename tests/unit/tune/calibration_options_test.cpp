// The fit policy every front end shares (calibration_options): the SVR is tuned unless C
// and σ are both given, with the solver's values C = 100, σ = 1 when not given; a value
// tuning would replace is refused.
#include <gtest/gtest.h>

#include "thermodrift/error.hpp"
#include "thermodrift/models/svr.hpp"
#include "thermodrift/tune/calibration.hpp"

namespace thermodrift {
namespace {

TEST(CalibrationOptions, TheSvrIsTunedUnlessCAndSigmaAreBothGiven) {
  FitRequest request;
  request.model = ModelKind::svr;
  request.seed = 7;
  request.threads = 3;
  const CalibrationOptions tuned = calibration_options(request);
  ASSERT_TRUE(tuned.tuning.has_value());
  EXPECT_EQ(tuned.tuning->method, TuneMethod::afsa);
  EXPECT_EQ(tuned.tuning->seed, 7u);
  EXPECT_EQ(tuned.tuning->threads, 3);
  EXPECT_EQ(tuned.tuning->evaluations, 49);
  EXPECT_EQ(tuned.svr.C, 100.0);
  EXPECT_EQ(tuned.svr.gamma, gamma_of_sigma(1.0));

  request.C = 10;
  request.sigma = 2;
  const CalibrationOptions fixed = calibration_options(request);
  EXPECT_FALSE(fixed.tuning.has_value());
  EXPECT_EQ(fixed.svr.C, 10.0);
  EXPECT_EQ(fixed.svr.gamma, gamma_of_sigma(2.0));

  request.C.reset();
  request.sigma.reset();
  request.tune = "grid";
  ASSERT_TRUE(calibration_options(request).tuning.has_value());
  EXPECT_EQ(calibration_options(request).tuning->method, TuneMethod::grid);
}

TEST(CalibrationOptions, AValueTuningWouldReplaceIsAUsageError) {
  const auto message = [](const FitRequest& request) {
    try {
      calibration_options(request);
    } catch (const UsageError& error) {
      return std::string(error.what());
    }
    return std::string("no error");
  };
  FitRequest request;
  request.model = ModelKind::svr;
  request.C = 10;  // alone: tuning would choose C
  EXPECT_NE(message(request).find("--C alone would be replaced"), std::string::npos) << message(request);
  request.C.reset();
  request.gamma = 0.5;
  EXPECT_NE(message(request).find("--gamma alone would be replaced"), std::string::npos) << message(request);
  request.C = 10;
  request.tune = "afsa";  // both given, and tuning asked for
  EXPECT_NE(message(request).find("--C with --tune"), std::string::npos) << message(request);
  request.tune.reset();
  EXPECT_EQ(message(request), "no error");
}

TEST(CalibrationOptions, SigmaAndGammaTogetherOrAnUnknownMethodAreUsageErrors) {
  FitRequest request;
  request.model = ModelKind::svr;
  request.sigma = 1;
  request.gamma = 0.5;
  EXPECT_THROW(calibration_options(request), UsageError);
  request.gamma.reset();
  request.tune = "simplex";
  EXPECT_THROW(calibration_options(request), UsageError);
}

TEST(CalibrationOptions, OtherModelsAreNeverTuned) {
  FitRequest request;
  request.model = ModelKind::linear;
  request.decimation = 3;
  request.threads = 2;
  const CalibrationOptions options = calibration_options(request);
  EXPECT_FALSE(options.tuning.has_value());
  EXPECT_EQ(options.decimation, std::optional<std::size_t>(3));
  EXPECT_EQ(options.selection.threads, 2);
}

}  // namespace
}  // namespace thermodrift
