# Fails when a source file includes what its layer may not (docs/architecture.md, "The layers"):
# a dispel header of a layer above it, or a library its room must not use (the core: no ROS, no
# files, no printing; the formats' and jobs' rooms: no bag library outside io_ros1_bags, no MRPT
# outside io_mrpt_rawlog and slam; the ROS 1 nodes: no bags, no rawlogs and no jobs). Tests (*_test.cpp) may use any room of their layer and below, and
# the real libraries they check against.
#
#   cmake -DSOURCE_DIR=<repository> [-DMIN_FILES=100] -P check_layers.cmake
cmake_policy(SET CMP0057 NEW)

# room: the folder, the dispel headers it may include, and the system headers it must not.
set(rooms
  "1-core/core|core|ros/ rosbag/ yaml-cpp/ iostream fstream cstdio cairo"
  "1-core/sim|core sim|ros/ rosbag/ yaml-cpp/ iostream fstream cstdio cairo"
  "1-core/eval|core eval|ros/ rosbag/ yaml-cpp/ iostream fstream cstdio cairo"
  "1-core/pipeline|core pipeline|ros/ rosbag/ yaml-cpp/ iostream fstream cstdio cairo"
  "2-formats/io|core sim eval pipeline io|ros/ rosbag/ sensor_msgs/ nav_msgs/ tf2_msgs/ cairo mrpt/"
  "2-formats/ros1_messages|core sim eval pipeline io|rosbag/ cairo mrpt/"
  "2-formats/ros1_bags|core sim eval pipeline io|cairo mrpt/"
  "2-formats/ros2_messages|core sim eval pipeline io|ros/ rosbag/ sensor_msgs/ nav_msgs/ tf2_msgs/ cairo mrpt/ zstd lz4 yaml-cpp/ cstdio fstream iostream"
  "2-formats/rosbag2|core sim eval pipeline io|ros/ rosbag/ sensor_msgs/ nav_msgs/ tf2_msgs/ cairo mrpt/"
  "2-formats/mrpt_rawlog|core sim eval pipeline io|ros/ rosbag/ sensor_msgs/ nav_msgs/ tf2_msgs/ cairo"
  "3-jobs/jobs|core sim eval pipeline io jobs|ros/ rosbag/ sensor_msgs/ nav_msgs/ tf2_msgs/ cairo mrpt/"
  "3-jobs/render|core sim eval pipeline io jobs render|ros/ rosbag/ sensor_msgs/ mrpt/"
  "3-jobs/slam|core sim eval pipeline io jobs slam|ros/ rosbag/ sensor_msgs/ cairo"
  "4-frontends/ros1|core pipeline io ros1|rosbag/ cairo mrpt/"
  "4-frontends/ros2|core pipeline io ros2|ros/ rosbag/ sensor_msgs/ cairo mrpt/"
  "4-frontends/cli|core sim eval pipeline io jobs render slam|ros/ rosbag/"
  "4-frontends/bench|core sim eval pipeline|ros/ rosbag/"
  "4-frontends/soak|core sim pipeline io|ros/ rosbag/ cairo mrpt/")
# Headers of a room that a room above may not use even though its layer is below (the ROS 1 bag
# library is for the jobs' recordings, not for a live node).
set(ros1_forbidden_headers "dispel/io/ros1_bag.hpp" "dispel/io/mrpt_rawlog.hpp"
                           "dispel/io/rosbag2.hpp")

set(layer_of_room_core 1)
set(layer_of_room_sim 1)
set(layer_of_room_eval 1)
set(layer_of_room_pipeline 1)
set(layer_of_room_io 2)
set(layer_of_room_jobs 3)
set(layer_of_room_render 3)
set(layer_of_room_slam 3)
set(layer_of_room_ros1 4)
set(layer_of_room_ros2 4)

set(violations "")
set(files_checked 0)
foreach(entry ${rooms})
  string(REPLACE "|" ";" parts "${entry}")
  list(GET parts 0 folder)
  list(GET parts 1 allowed)
  list(GET parts 2 forbidden)
  string(REPLACE " " ";" allowed "${allowed}")
  string(REPLACE " " ";" forbidden "${forbidden}")
  string(REGEX MATCH "^[0-9]" layer "${folder}")
  file(GLOB_RECURSE sources ${SOURCE_DIR}/${folder}/*.cpp ${SOURCE_DIR}/${folder}/*.hpp)
  foreach(src ${sources})
    math(EXPR files_checked "${files_checked} + 1")
    get_filename_component(name ${src} NAME)
    string(REGEX MATCH "_test\\.cpp$" is_test "${name}")
    file(STRINGS ${src} includes REGEX "^[ \t]*#[ \t]*include[ \t]*[<\"]")
    file(RELATIVE_PATH rel ${SOURCE_DIR} ${src})
    foreach(line ${includes})
      string(REGEX REPLACE "^[ \t]*#[ \t]*include[ \t]*[<\"]([^>\"]+)[>\"].*" "\\1" header "${line}")
      if(header MATCHES "^dispel/([a-z0-9_]+)/")
        set(room "${CMAKE_MATCH_1}")
        if(is_test)
          # Tests: any room of their layer or below.
          if(DEFINED layer_of_room_${room} AND layer_of_room_${room} GREATER layer)
            list(APPEND violations "${rel}: includes ${header} (layer ${layer_of_room_${room}})")
          endif()
        elseif(NOT room IN_LIST allowed)
          list(APPEND violations "${rel}: includes ${header}, which ${folder} may not use")
        elseif(folder STREQUAL "4-frontends/ros1" AND header IN_LIST ros1_forbidden_headers)
          list(APPEND violations "${rel}: includes ${header}: a live node reads no bags")
        endif()
      elseif(NOT is_test)
        foreach(f ${forbidden})
          string(FIND "${header}" "${f}" at)
          if(at EQUAL 0)
            list(APPEND violations "${rel}: includes <${header}>, which ${folder} may not use")
          endif()
        endforeach()
      endif()
    endforeach()
  endforeach()
endforeach()

if(NOT DEFINED MIN_FILES)
  set(MIN_FILES 100)
endif()
if(files_checked LESS MIN_FILES)
  message(FATAL_ERROR "only ${files_checked} files found under ${SOURCE_DIR}: wrong folder?")
endif()
if(violations)
  list(JOIN violations "\n  " text)
  message(FATAL_ERROR "layer rules broken:\n  ${text}")
endif()
message(STATUS "${files_checked} files follow the layers' include rules")
