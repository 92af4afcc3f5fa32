// dfbwall: a thin main; everything happens in app::run.
#include "apps/Run.h"
#include "renderers/picture/PictureRenderer.h"
#include "renderers/scivis/Registration.h"

int main(int argc, char** argv) {
  renderers::scivis::registerSciVis();  // the scivis renderer and the scivis parts of scene files
  renderers::picture::registerPictures();  // ready-made pictures: `dfbwall show`
  return app::run(argc, argv);
}
