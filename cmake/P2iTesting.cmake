# p2i_add_catch_tests(TARGET SOURCES a.cc b.cc LIBS lib1 lib2)
#
# One Catch2 test binary per source folder. Every TEST_CASE carries exactly one of the tags
# [unit], [integration] or [slow]; each becomes the ctest label of the same name, so
# `ctest -L unit` is the quick subset. A test case with none of the three runs as `unit`
# (never silently skipped).
#
# A test case that cannot run here (no ../shared data or LPIPS weights, no camera tool) calls
# P2I_SKIP (tests/skip.h), which prints "SKIPPED: <why>": SKIP_REGULAR_EXPRESSION makes ctest
# report it as skipped, not passed.
function(p2i_add_catch_tests target)
  cmake_parse_arguments(ARG "" "" "SOURCES;LIBS" ${ARGN})
  add_executable(${target} ${ARG_SOURCES})
  target_link_libraries(${target} PRIVATE p2i_catch_main ${ARG_LIBS})
  target_compile_definitions(${target} PRIVATE
    P2I_SOURCE_DIR="${PROJECT_SOURCE_DIR}"
    P2I_BINARY_DIR="${PROJECT_BINARY_DIR}"
    P2I_SHARED_DIR_DEFAULT="${P2I_SHARED_DIR_DEFAULT}")
  set(props ENVIRONMENT "P2I_BIN_DIR=${PROJECT_BINARY_DIR}/bin"
            SKIP_REGULAR_EXPRESSION "SKIPPED:")
  catch_discover_tests(${target} TEST_SPEC "[unit]"
    PROPERTIES LABELS unit TIMEOUT 300 ${props})
  catch_discover_tests(${target} TEST_SPEC "[integration]"
    PROPERTIES LABELS integration TIMEOUT 600 ${props})
  catch_discover_tests(${target} TEST_SPEC "[slow]"
    PROPERTIES LABELS slow TIMEOUT 1200 ${props})
  catch_discover_tests(${target} TEST_SPEC "~[unit]~[integration]~[slow]"
    PROPERTIES LABELS unit TIMEOUT 300 ${props})
endfunction()
