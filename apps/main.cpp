// dfbwall: a thin main; everything happens in app::run.
#include "apps/Run.h"
#include "renderers/scivis/Registration.h"

int main(int argc, char** argv) {
  renderers::scivis::registerSciVis();  // the scivis renderer and the scivis parts of scene files
  return app::run(argc, argv);
}
