// strata_pack_makehuman DIR OUT: writes the compact MakeHuman source the default body is derived from
// (io/makehuman_pack.h) from a MakeHuman hm08 folder (base.obj, default.mhskel, default_weights.mhw), through the
// same importer `--mesh DIR` uses. A maintainer's tool: data/makehuman_body.bin was written by
//   build/strata_pack_makehuman ../shared/data/makehuman_hm08 data/makehuman_body.bin
// and tests/rig/makehuman_body_test.cpp checks the shipped file against a fresh pack where the folder is present.
#include <cstdio>
#include <exception>
#include <filesystem>

#include "io/atomic_file.h"
#include "io/makehuman.h"
#include "io/makehuman_pack.h"

int main(int argc, char** argv) {
  if (argc != 3) {
    std::fprintf(stderr, "usage: strata_pack_makehuman MAKEHUMAN_DIR OUT\n");
    return 2;
  }
  try {
    const std::string packed = strata::pack_makehuman_source(strata::makehuman_source_from(strata::load_makehuman(argv[1])));
    strata::write_file_atomically(argv[2], packed);
    std::printf("%s: %zu bytes\n", argv[2], packed.size());
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "strata_pack_makehuman: %s\n", e.what());
    return 1;
  }
}
