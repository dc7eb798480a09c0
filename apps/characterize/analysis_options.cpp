#include "analysis_options.hpp"

#include "metro/noise/allan.hpp"

namespace metro::apps {

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
  type_a.sensors = o.sensors;
  type_a.quantities = o.quantities;
  type_a.threads = threads;
  out->plot.threads = threads;
  std::string why;
  if (!out->IsValid(&why)) return MakeError(why);
  if (!o.tag_registry.empty()) {
    auto loaded = TagRegistry::Load(o.tag_registry);
    if (!loaded.ok()) return loaded.error();
    out->registry = loaded.value();
  }
  if (o.allan) {
    out->allan = true;
    out->allan_options = o.allan_options;
    out->allan_options.allan.threads = threads;
    out->allan_options.quantities = o.quantities;
  }
  return Status::Ok();
}

}  // namespace metro::apps
