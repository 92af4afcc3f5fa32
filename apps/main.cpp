// dfbwall: a thin main; everything happens in app::run.
#include "apps/Run.h"

int main(int argc, char** argv) { return app::run(argc, argv); }
