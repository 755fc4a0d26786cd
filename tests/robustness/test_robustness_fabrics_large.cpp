// Robustness corpus, the fabric cases over ~15 s (ctest label robustness_large): larger
// repeats (twill 2/2 and 3/1 on 4 x 4 samples, satin 5 and 8 on 5 x 5 and 8 x 8), the
// matrix weave and the paper's tows of 48 fibers on a 2 x 2 sample, checked as the small ones
// are (robustness/fabric_support.hpp, test_robustness_fabrics.cpp).
#include <gtest/gtest.h>

#include "robustness/fabric_support.hpp"

namespace fibra::test {
namespace {

class FabricBiaxialLarge : public ::testing::TestWithParam<BiaxialCase> {};

TEST_P(FabricBiaxialLarge, WovenRelaxedAndPulled) { run_biaxial_case(GetParam()); }

INSTANTIATE_TEST_SUITE_P(Robustness, FabricBiaxialLarge,
                         ::testing::Values(BiaxialCase{"fabric_twill22_biaxial", 2.0, false, 60},
                                           BiaxialCase{"fabric_twill31_biaxial", 1.0, false, 60},
                                           BiaxialCase{"fabric_satin5_biaxial", 1.0, false, 60},
                                           BiaxialCase{"fabric_satin8_biaxial", 1.0, false, 300},
                                           BiaxialCase{"fabric_matrix_biaxial", 0.5, false, 60},
                                           BiaxialCase{"fabric_paper_tows_48", 1.0, true, 900}),
                         [](const auto& p) { return std::string(p.param.name); });

}  // namespace
}  // namespace fibra::test
