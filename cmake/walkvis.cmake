# Shared build rules for walkvis' libraries.
set(WALKVIS_WARNINGS -Wall -Wextra -Wshadow)

# walkvis_library(NAME DIR [DEPS ...] [PRIVATE_DEPS ...])
# Globs DIR/*.cpp. Files named *_cgal.cpp go into NAME_cgal, a static library of their own that
# links CGAL::CGAL PRIVATE: CGAL headers cost seconds per translation unit and CGAL adds
# -frounding-math to whatever links it, so only those few files pay for it.
function(walkvis_library name dir)
  cmake_parse_arguments(ARG "" "" "DEPS;PRIVATE_DEPS" ${ARGN})
  file(GLOB sources CONFIGURE_DEPENDS ${dir}/*.cpp)
  file(GLOB cgal_sources CONFIGURE_DEPENDS ${dir}/*_cgal.cpp)
  if(cgal_sources)
    list(REMOVE_ITEM sources ${cgal_sources})
  endif()
  if(NOT sources AND NOT cgal_sources)
    # A stage not written yet: a header-only placeholder so the others link against it.
    add_library(${name} INTERFACE)
    target_include_directories(${name} INTERFACE ${PROJECT_SOURCE_DIR})
    target_link_libraries(${name} INTERFACE glm::glm ${ARG_DEPS})
    return()
  endif()
  add_library(${name} STATIC ${sources})
  target_include_directories(${name} PUBLIC ${PROJECT_SOURCE_DIR})
  target_compile_options(${name} PRIVATE ${WALKVIS_WARNINGS})
  target_link_libraries(${name} PUBLIC glm::glm ${ARG_DEPS} PRIVATE ${ARG_PRIVATE_DEPS})
  if(cgal_sources)
    add_library(${name}_cgal STATIC ${cgal_sources})
    target_include_directories(${name}_cgal PUBLIC ${PROJECT_SOURCE_DIR})
    target_compile_options(${name}_cgal PRIVATE ${WALKVIS_WARNINGS})
    target_link_libraries(${name}_cgal PUBLIC glm::glm ${ARG_DEPS} PRIVATE CGAL::CGAL)
    target_link_libraries(${name} PRIVATE ${name}_cgal)
    # The CGAL half may call back into the rest of its library: a cycle CMake resolves by
    # repeating the two static libraries on the link line.
    target_link_libraries(${name}_cgal PRIVATE ${name})
    # Twice is not always enough: an object pulled in on the second pass may need the other half
    # again (a test that uses one file of the library).
    set_property(TARGET ${name} ${name}_cgal PROPERTY LINK_INTERFACE_MULTIPLICITY 3)
  endif()
endfunction()
