# Helpers applied per target: warnings are set here, once, and never globally.
function(dispel_set_warnings target)
  if(CMAKE_CXX_COMPILER_ID MATCHES "GNU|Clang")
    target_compile_options(${target} PRIVATE -Wall -Wextra -Wpedantic -Wshadow -Wconversion
                                             -Wno-sign-conversion -Wnull-dereference
                                             $<$<COMPILE_LANGUAGE:CXX>:-Wnon-virtual-dtor>
                                             $<$<COMPILE_LANGUAGE:CXX>:-Wold-style-cast>)
  elseif(MSVC)
    target_compile_options(${target} PRIVATE /W4)
  endif()
endfunction()

# One GoogleTest executable per unit; each TEST becomes a ctest entry.
function(dispel_add_test name source)
  add_executable(${name} ${source})
  target_link_libraries(${name} PRIVATE ${ARGN} GTest::gtest GTest::gtest_main)
  target_compile_definitions(${name} PRIVATE
    DISPEL_SOURCE_DIR="${PROJECT_SOURCE_DIR}")
  dispel_set_warnings(${name})
  gtest_discover_tests(${name} DISCOVERY_TIMEOUT 60)
endfunction()

# An exported library dispel::<name> (target dispel_<name>) with its public headers in include/
# beside the calling CMakeLists.txt, installed into the dispelTargets export set.
function(dispel_add_library name)
  add_library(dispel_${name} ${ARGN})
  add_library(dispel::${name} ALIAS dispel_${name})
  set_target_properties(dispel_${name} PROPERTIES EXPORT_NAME ${name} OUTPUT_NAME dispel_${name}
                                                  POSITION_INDEPENDENT_CODE ON)
  target_compile_features(dispel_${name} PUBLIC cxx_std_17)
  target_include_directories(dispel_${name} PUBLIC
    $<BUILD_INTERFACE:${CMAKE_CURRENT_SOURCE_DIR}/include>
    $<INSTALL_INTERFACE:${CMAKE_INSTALL_INCLUDEDIR}>)
  dispel_set_warnings(dispel_${name})
  install(TARGETS dispel_${name} EXPORT dispelTargets
    ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
    LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR}
    RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
  install(DIRECTORY include/ DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
endfunction()
