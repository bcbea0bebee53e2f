#include "fvm/identify_options.h"

#include "fvm/commands.h"

namespace fvm::cli {

void AddIdentifyOptions(CLI::App& app, workflows::IdentifySettings& settings) {
  app.add_option("--anchor", settings.anchor,
                 "how stitched measurements are referenced: 'none' ([Pérez 2019] procedure: every placement starts at "
                 "one spot) or 'first-tile' (each placement anchored at the stage error of its own first tile)")
      ->check(CLI::IsMember({"none", "first-tile"}))
      ->capture_default_str();
  app.add_option("--stitched-frame", settings.stitched_frame,
                 "how each stitched export sits in the stage frame: 'rotated' (the instrument registers tiles by "
                 "translation, so the mosaic keeps the orientation of its first tile, turned with the stage there; "
                 "first-tile figures turn it by the model's rotation terms, or, for a model without rotation terms of "
                 "order 1 or more, carry the turn's spread in their prediction) or 'translated' (the turn left out)")
      ->check(CLI::IsMember({"rotated", "translated"}))
      ->capture_default_str();
  app.add_option("--loss", settings.loss, "robust loss on each centre's Euclidean error")
      ->check(CLI::IsMember({"none", "huber", "cauchy"}))
      ->capture_default_str();
  app.add_option("--loss-scale-um", settings.loss_scale_um, "error (um) where the robust loss starts to bend")
      ->check(Within(1e-3, 1e5, "um"))
      ->capture_default_str();
}

workflows::IdentifySettings Threaded(workflows::IdentifySettings settings) {
  settings.threads = ThreadCount();
  return settings;
}

}  // namespace fvm::cli
