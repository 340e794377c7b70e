#include <catch2/catch.hpp>

#include "brdfz/errors.h"
#include "brdfz/repr/spec.h"

using brdfz::ReprSpec;

TEST_CASE("ReprSpec parses kinds, options and the positional model", "[spec]") {
    const ReprSpec svd = ReprSpec::parse("svd:rank=4,space=log");
    CHECK(svd.kind() == "svd");
    CHECK(svd.get_int("rank", 1, 1, 64) == 4);
    CHECK(svd.get_choice("space", "linear", {"linear", "log"}) == "log");
    CHECK_NOTHROW(svd.finish());
    CHECK(svd.str() == "svd:rank=4,space=log");

    const ReprSpec tab = ReprSpec::parse("tabular:res=45x45x90,dtype=f16");
    CHECK(tab.get_dims("res", {90, 90, 180}) == std::vector<int>{45, 45, 90});
    CHECK(tab.get_string("dtype", "f32") == "f16");

    const ReprSpec analytic = ReprSpec::parse("analytic:lambert+ggx,loss=log");
    CHECK(analytic.positional() == "lambert+ggx");
    CHECK(analytic.get_string("loss", "cos") == "log");
    CHECK(analytic.str() == "analytic:lambert+ggx,loss=log");

    const ReprSpec bare = ReprSpec::parse("nmf");
    CHECK(bare.get_int("rank", 3, 1, 64) == 3);
    CHECK_NOTHROW(bare.finish());
}

TEST_CASE("ReprSpec rejects malformed specs and unknown or bad options", "[spec]") {
    CHECK_THROWS_AS(ReprSpec::parse(":rank=4"), brdfz::ValueError);
    CHECK_THROWS_AS(ReprSpec::parse("svd:rank=4,rank=5"), brdfz::ValueError);
    CHECK_THROWS_AS(ReprSpec::parse("svd:rank=4,log"), brdfz::ValueError);
    CHECK_THROWS_AS(ReprSpec::parse("svd:=4"), brdfz::ValueError);

    const ReprSpec spec = ReprSpec::parse("svd:rank=four,rnak=3,res=4x0,space=cube");
    CHECK_THROWS_AS(spec.get_int("rank", 1, 1, 64), brdfz::ValueError);
    CHECK_THROWS_AS(spec.get_dims("res", {1, 1}), brdfz::ValueError);
    CHECK_THROWS_AS(spec.get_choice("space", "linear", {"linear", "log"}), brdfz::ValueError);
    CHECK_THROWS_WITH(spec.finish(), Catch::Contains("rnak"));
    CHECK_THROWS_AS(ReprSpec::parse("svd:rank=99").get_int("rank", 1, 1, 64), brdfz::ValueError);
    CHECK_THROWS_AS(ReprSpec::parse("x:res=4x4").get_dims("res", {1, 1, 1}), brdfz::ValueError);
}
