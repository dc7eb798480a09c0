// The flags `characterize SESSION`, `analyze`, `batch` and `accuracy` share (analysis_options.hpp).
// Included by main.cpp only: the program's one translation unit with CLI11 (issue #39).
#pragma once

#include <CLI/CLI.hpp>

#include "analysis_options.hpp"
#include "cli_flags.hpp"
#include "metro/noise/allan.hpp"

namespace metro::apps {

inline void AddAnalysisCliOptions(CLI::App* app, AnalysisCliOptions* o,
                                  AnalysisCliKind kind = AnalysisCliKind::kTypeA) {
  const bool type_a = kind == AnalysisCliKind::kTypeA;
  AddLoadCliOptions(app, &o->load);
  app->add_option("--skip-samples", o->window.skip_samples,
                  "drop the first N observations of each tag")
      ->check(CLI::NonNegativeNumber);
  app->add_option("--skip-seconds", o->window.skip_seconds,
                  "drop each tag's observations in its first S seconds")
      ->check(CLI::NonNegativeNumber);
  app->add_option("--from-s", o->window.from_s, "keep observations with t_s >= this");
  app->add_option("--to-s", o->window.to_s, "keep observations with t_s <= this");
  // none|auto -> WindowOptions::settle_auto.
  app->add_option_function<std::string>(
         "--settle", [o](const std::string& value) { o->window.settle_auto = value == "auto"; },
         type_a ? "auto: drop each quantity's start-up transient (fitted exponential, "
                  "cut where the rest biases the mean by <= 0.1 u; docs/type-a.md)"
                : "auto: also drop each plateau's start-up transient (MSER-5; "
                  "docs/accuracy.md)")
      ->check(CLI::IsMember({"none", "auto"}))
      ->default_str(o->window.settle_auto ? "auto" : "none");
  app->add_option("--tags,--tag-registry", o->tag_registry,
                  R"(tags file, JSON {"1": "Forehead", "2": {"name": "Chest", "device_id": ...}} )"
                  R"(naming the tags (docs/formats.md "Tags file"; default: thesis Table 5.2))")
      ->check(CLI::ExistingFile);
  if (!type_a) {
    app->add_option("--sensor", o->sensors, "the tag to evaluate (default: the first)");
    return;
  }
  // quantity|tag -> WindowOptions::settle_tag_wide.
  app->add_option_function<std::string>(
         "--settle-scope",
         [o](const std::string& value) { o->window.settle_tag_wide = value == "tag"; },
         "with --settle auto: quantity (each from its own settle point) or tag (every "
         "quantity of a tag from the largest non-temperature cut)")
      ->check(CLI::IsMember({"quantity", "tag"}))
      ->default_str(o->window.settle_tag_wide ? "tag" : "quantity");
  app->add_option("--sensor", o->sensors, "only this tag (repeatable)");
  app->add_option("--quantity", o->quantities, "only this quantity, e.g. pitch_deg (repeatable)");
  app->add_flag("--allan", o->allan,
                "Allan deviation and IEEE 952 noise terms of the rate quantities (docs/noise.md)");
  // The library's parsers, so the flags accept exactly what the library does; a value they
  // refuse is a usage error naming the flag (exit 2).
  app->add_option_function<std::string>(
         "--taus",
         [o](const std::string& value) {
           Result<TauSpacing> taus = ParseTauSpacing(value);
           if (!taus.ok()) throw CLI::ValidationError("--taus", taus.error().message);
           o->allan_options.allan.taus = taus.value();
         },
         "Allan taus: octave, decade:N, all")
      ->default_str(TauSpacingName(o->allan_options.allan.taus));
  app->add_option_function<std::string>(
         "--estimator",
         [o](const std::string& value) {
           Result<AllanEstimator> estimator = ParseAllanEstimator(value);
           if (!estimator.ok())
             throw CLI::ValidationError("--estimator", estimator.error().message);
           o->allan_options.allan.estimator = estimator.value();
         },
         "Allan estimator: oadev, mdev, ohdev")
      ->default_str(AllanEstimatorName(o->allan_options.allan.estimator));
  app->add_option_function<std::string>(
         "--gaps",
         [o](const std::string& value) {
           Result<AllanGapPolicy> gaps = ParseAllanGapPolicy(value);
           if (!gaps.ok()) throw CLI::ValidationError("--gaps", gaps.error().message);
           o->allan_options.gaps = gaps.value();
         },
         "Allan through missing samples: skip (leave out the terms that read one, "
         "NIST SP 1065), split (the longest gap-free stretch only) or refuse "
         "(docs/noise.md)")
      ->check(CLI::IsMember({"skip", "split", "refuse"}))
      ->default_str(AllanGapPolicyName(o->allan_options.gaps));
}

}  // namespace metro::apps
