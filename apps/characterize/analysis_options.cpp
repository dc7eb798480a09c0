#include "analysis_options.hpp"

#include "metro/noise/allan.hpp"

namespace metro::apps {

void AddAnalysisCliOptions(CLI::App* app, AnalysisCliOptions* o, AnalysisCliKind kind) {
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
  app->add_option("--settle", o->settle,
                  type_a ? "auto: drop each quantity's start-up transient (fitted exponential, "
                           "cut where the rest biases the mean by <= 0.1 u; docs/type-a.md)"
                         : "auto: also drop each plateau's start-up transient (MSER-5; "
                           "docs/accuracy.md)")
      ->check(CLI::IsMember({"none", "auto"}))
      ->capture_default_str();
  app->add_option("--tags,--tag-registry", o->tag_registry,
                  R"(tags file, JSON {"1": "Forehead", "2": {"name": "Chest", "device_id": ...}} )"
                  R"(naming the tags (docs/formats.md "Tags file"; default: thesis Table 5.2))")
      ->check(CLI::ExistingFile);
  if (!type_a) {
    app->add_option("--sensor", o->sensors, "the tag to evaluate (default: the first)");
    return;
  }
  app->add_option("--settle-scope", o->settle_scope,
                  "with --settle auto: quantity (each from its own settle point) or tag (every "
                  "quantity of a tag from the largest non-temperature cut)")
      ->check(CLI::IsMember({"quantity", "tag"}))
      ->capture_default_str();
  app->add_option("--sensor", o->sensors, "only this tag (repeatable)");
  app->add_option("--quantity", o->quantities, "only this quantity, e.g. pitch_deg (repeatable)");
  app->add_flag("--allan", o->allan,
                "Allan deviation and IEEE 952 noise terms of the rate quantities (docs/noise.md)");
  app->add_option("--taus", o->taus, "Allan taus: octave, decade:N, all")->capture_default_str();
  app->add_option("--estimator", o->estimator, "Allan estimator: oadev, mdev, ohdev")
      ->capture_default_str();
  app->add_option("--gaps", o->gaps,
                  "Allan through missing samples: skip (leave out the terms that read one, "
                  "NIST SP 1065), split (the longest gap-free stretch only) or refuse "
                  "(docs/noise.md)")
      ->check(CLI::IsMember({"skip", "split", "refuse"}))
      ->capture_default_str();
}

WindowOptions AccuracyWindow(const AnalysisCliOptions& o) {
  WindowOptions window = o.window;
  window.settle_auto = false;  // The plateaus settle by their own rule (docs/accuracy.md).
  window.settle_tag_wide = false;
  return window;
}

Status MakeSessionAnalysisOptions(const AnalysisCliOptions& o, int threads,
                                  SessionAnalysisOptions* out) {
  LoadOptions& load = out->load;
  if (Status s = MakeLoadOptions(o.load, &load); !s.ok()) return s;
  load.threads = threads;
  SessionTypeAOptions& type_a = out->type_a;
  type_a.window = o.window;
  type_a.window.settle_auto = o.settle == "auto";
  type_a.window.settle_tag_wide = o.settle_scope == "tag";
  type_a.sensors = o.sensors;
  type_a.quantities = o.quantities;
  type_a.threads = threads;
  std::string why;
  if (!out->IsValid(&why)) return MakeError(why);
  if (!o.tag_registry.empty()) {
    auto loaded = TagRegistry::Load(o.tag_registry);
    if (!loaded.ok()) return loaded.error();
    out->registry = loaded.value();
  }
  if (o.allan) {
    auto taus = ParseTauSpacing(o.taus);
    if (!taus.ok()) return taus.error();
    auto estimator = ParseAllanEstimator(o.estimator);
    if (!estimator.ok()) return estimator.error();
    out->allan = true;
    out->allan_options.allan.taus = taus.value();
    out->allan_options.allan.estimator = estimator.value();
    out->allan_options.allan.threads = threads;
    out->allan_options.quantities = o.quantities;
    auto gaps = ParseAllanGapPolicy(o.gaps);
    if (!gaps.ok()) return gaps.error();
    out->allan_options.gaps = gaps.value();
  }
  return Status::Ok();
}

}  // namespace metro::apps
