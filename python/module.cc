// `import fvm`: the workflows of the fvm command line for people who script in notebooks, numpy arrays in and out.
// Each concept binds itself (bindings.h); importing the module loads neither OpenImageIO nor PCL: they are dlopen
// plugins (imaging/io/plugin_loader.h) loaded by the first reader that needs them.

#include <glog/logging.h>

#include "core/version.h"
#include "python/bindings.h"

PYBIND11_MODULE(fvm, m) {
  // Ceres reports through glog; as in the command line (fvm/main.cc), only a fatal check, which aborts, is logged:
  // fvm says what matters in its results and exceptions.
  FLAGS_minloglevel = google::GLOG_FATAL;
  FLAGS_stderrthreshold = google::GLOG_FATAL;
  FLAGS_logtostderr = false;
  if (!google::IsGoogleLoggingInitialized()) google::InitGoogleLogging("fvm");
  m.doc() =
      "fvm: calibrate the motion stage of focus-variation microscopes (and machine tools measured with laser "
      "trackers).\n\nThe command line's jobs as functions, numpy arrays in and out. Units: mm and rad (keys and "
      "attributes ending in _um say micrometres).\n\nExample:\n    >>> import fvm\n"
      "    >>> cal = fvm.calibrate('samples/bar17', model=27)\n    >>> cal.parameters['names'][:3]";
  m.attr("__version__") = fvm::Version();
  m.attr("__git_commit__") = fvm::GitCommit();  // as `fvm --version` names it
  fvm::python::BindErrors(m);
  fvm::python::BindResults(m);
  fvm::python::BindSurfaces(m);
  fvm::python::BindFits(m);
  fvm::python::BindCalibration(m);
  fvm::python::BindMachine(m);
  fvm::python::BindTestPiece(m);
  fvm::python::BindTracker(m);
  fvm::python::BindStitching(m);
  fvm::python::BindTiles(m);
  fvm::python::BindFocus(m);
  fvm::python::BindStageJobs(m);
  fvm::python::BindDiff(m);
  fvm::python::BindSimulate(m);
}
