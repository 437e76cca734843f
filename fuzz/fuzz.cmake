# libFuzzer targets, one per loader (STRATA_FUZZ=ON; clang only: libFuzzer ships with clang's runtime, Debian
# packages clang-14 and libclang-rt-14-dev). Included from the top-level CMakeLists.txt so the generated embedded
# data source is visible. Build with `cmake --build build-fuzz --target strata_fuzz_all`; run with
# `bash scripts/strata.sh fuzz [SECONDS]`, which also builds the seed corpora (fuzz/build_corpus.sh).
#
# The loaders are compiled once more, instrumented (coverage for libFuzzer, AddressSanitizer, UBSan that aborts),
# into a static library of only what they need; the rest of the engine (GL, OpenImageIO, the GCC-only skinning
# kernel clones) plays no part in parsing.
if(NOT CMAKE_CXX_COMPILER_ID STREQUAL "Clang")
  message(FATAL_ERROR "STRATA_FUZZ needs clang (libFuzzer): configure with -DCMAKE_CXX_COMPILER=clang++-14")
endif()
set(STRATA_FUZZ_FLAGS -fsanitize=address,undefined -fno-sanitize-recover=all -fno-omit-frame-pointer -gline-tables-only)
add_library(strata_fuzz_loaders STATIC
  components/skeleton.cpp
  components/mesh.cpp
  components/humanoid_shape.cpp
  io/hanim_x3d.cpp
  io/hanim_paper_xml.cpp
  io/hanim_loader.cpp
  io/xml_util.cpp
  io/bvh.cpp
  io/obj.cpp
  io/mesh_check.cpp
  io/makehuman.cpp
  io/makehuman_pack.cpp
  io/gltf.cpp
  rig/binding.cpp
  rig/harmonic_weights.cpp
  io/muscle_file.cpp
  io/scenario_file.cpp
  io/retarget_map_file.cpp
  motion/bvh_naming.cpp
  rig/muscle_binding.cpp
  ${STRATA_EMBED_CPP})
target_include_directories(strata_fuzz_loaders PUBLIC ${CMAKE_CURRENT_SOURCE_DIR})
strata_unity_batches(strata_fuzz_loaders)
target_compile_options(strata_fuzz_loaders PUBLIC ${STRATA_FUZZ_FLAGS} PRIVATE -fsanitize=fuzzer-no-link ${STRATA_WARNINGS})
target_link_options(strata_fuzz_loaders PUBLIC -fsanitize=address,undefined)
target_link_libraries(strata_fuzz_loaders
  PUBLIC glm::glm
  PRIVATE pugixml::pugixml nlohmann_json::nlohmann_json TinyGLTF::TinyGLTF TBB::tbb ZLIB::ZLIB)

# One target per loader.
set(STRATA_FUZZ_TARGETS hanim obj bvh gltf makehuman makehuman_pack binding muscle scenario)
add_custom_target(strata_fuzz_all)
foreach(target ${STRATA_FUZZ_TARGETS})
  add_executable(fuzz_${target} fuzz/fuzz_${target}.cpp)
  target_compile_options(fuzz_${target} PRIVATE -fsanitize=fuzzer ${STRATA_WARNINGS})
  target_link_options(fuzz_${target} PRIVATE -fsanitize=fuzzer)
  target_link_libraries(fuzz_${target} PRIVATE strata_fuzz_loaders nlohmann_json::nlohmann_json)
  add_dependencies(strata_fuzz_all fuzz_${target})
endforeach()
