#pragma once
// Loops that vectorise well only with AVX2 (strided float -> double loads, wide exponentials) are
// compiled twice where the compiler can dispatch at load time (CAUSTICS_AVX2_CLONES): for AVX2 and for
// the baseline, picked once by the CPU. Neither version fuses a multiply and an add into an FMA (the
// method is compiled with -ffp-contract=off; the avx2 target has no FMA either), so an element-wise loop
// gives the same values on every machine; only the order in which a vectorised reduction adds its lanes
// depends on the instruction set (and is fixed for one machine).
#include <caustics/util/target_clones.hpp>
