// The amg.* keys (amg_settings.hpp) through the flat key space: every default reads back and is
// accepted as text, and a value outside a key's choices or bounds is refused naming the key.
#include "harness/params.hpp"
#include "core/error.hpp"

#include <gtest/gtest.h>

using namespace xb;

TEST(AmgSettings, EveryKeyRoundTripsItsDefault) {
  int keys = 0;
  for (const ParamField& f : param_fields()) {
    if (f.key.rfind("amg.", 0) != 0) continue;
    Params p;
    const std::string text = param_to_string(p, f);
    EXPECT_NO_THROW(set_param(p, f.key, text, "test")) << f.key << " = " << text;
    EXPECT_EQ(param_to_string(p, f), text) << f.key;
    ++keys;
  }
  EXPECT_GE(keys, 20);
}

TEST(AmgSettings, BadValuesAreRefusedNamingTheKey) {
  for (const auto& [key, value] : std::vector<std::pair<std::string, std::string>>{
           {"amg.smoother", "sor"}, {"amg.near_kernel", "constant"}, {"amg.max_levels", "0"}, {"amg.precision", "half"}}) {
    Params p;
    try {
      set_param(p, key, value, "--set");
      ADD_FAILURE() << key << "=" << value << " accepted";
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find(key), std::string::npos) << e.what();
    }
  }
}
