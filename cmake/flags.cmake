# One INTERFACE target carries the project's compile flags; every meltlab target links it.
add_library(meltlab_flags INTERFACE)
target_compile_features(meltlab_flags INTERFACE cxx_std_20)
target_compile_options(meltlab_flags INTERFACE
  -Wall -Wextra -Wpedantic -Wshadow -Wnon-virtual-dtor -Wcast-align -Wunused
  -Woverloaded-virtual -Wdouble-promotion -Wimplicit-fallthrough
  # Serial and parallel cycles must give bitwise-identical meshes. Identical source
  # expressions only give identical results if the compiler never fuses a*b+c into an FMA
  # in one code path and not in the other, so contraction is off everywhere.
  -ffp-contract=off
  # sqrt() need not set errno, so it compiles to the (exactly rounded) SIMD instruction.
  -fno-math-errno)
# The melt kernels are written so the compiler can vectorise them; let it use the machine's
# SIMD width. Results do not depend on the width (no contraction, no fast-math).
if(MELTLAB_NATIVE)
  target_compile_options(meltlab_flags INTERFACE -march=native)
endif()
if(MELTLAB_WERROR)
  target_compile_options(meltlab_flags INTERFACE -Werror)
endif()
if(MELTLAB_FUZZ)
  # libFuzzer builds (clang only, scripts/fuzz): every library is instrumented for coverage and
  # built with ASan + UBSan; the fuzz_* programs add libFuzzer's main (tests/fuzz).
  target_compile_options(meltlab_flags INTERFACE -fsanitize=fuzzer-no-link,address,undefined -fno-omit-frame-pointer -g)
  target_link_options(meltlab_flags INTERFACE -fsanitize=address,undefined)
endif()
if(MELTLAB_SANITIZE)
  target_compile_options(meltlab_flags INTERFACE
    -fsanitize=address,undefined -fno-sanitize-recover=undefined -fno-omit-frame-pointer
    # GCC's instrumentation defeats its own flow analysis: -Wmaybe-uninitialized then fires on
    # library templates inlined into our code (OpenMesh's PropertyT::push_back under GCC 12), a
    # documented false positive of sanitizer builds. The warning stays on in Release/Debug.
    -Wno-maybe-uninitialized)
  target_link_options(meltlab_flags INTERFACE -fsanitize=address,undefined)
endif()

# Third-party headers are included as system headers so their warnings do not fail -Werror.
function(meltlab_system_includes target)
  foreach(dep IN LISTS ARGN)
    if(TARGET ${dep})
      get_target_property(dirs ${dep} INTERFACE_INCLUDE_DIRECTORIES)
      if(dirs)
        target_include_directories(${target} SYSTEM PRIVATE ${dirs})
      endif()
    endif()
  endforeach()
endfunction()
