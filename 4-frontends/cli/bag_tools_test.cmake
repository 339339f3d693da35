# Run by ctest: a bag written by `dispel filter` must be readable by ROS's own tools: `rosbag info`
# and Debian's python3-rosbag (both need /usr/bin/python3, not the python3 first on PATH).
set(out ${WORK_DIR}/tools_check.bag)
file(MAKE_DIRECTORY ${WORK_DIR})
file(REMOVE ${out})
execute_process(COMMAND ${DISPEL} filter ${BAG} -o ${out} --static-sensor --compression bz2
                RESULT_VARIABLE rc OUTPUT_VARIABLE so ERROR_VARIABLE se)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "dispel filter failed (${rc}): ${se}")
endif()
execute_process(COMMAND /usr/bin/python3 /usr/bin/rosbag info ${out}
                RESULT_VARIABLE rc OUTPUT_VARIABLE info ERROR_VARIABLE se)
if(NOT rc EQUAL 0 OR NOT info MATCHES "/scan_filtered +1265 msgs +: sensor_msgs/LaserScan"
   OR NOT info MATCHES "compression: +bz2")
  message(FATAL_ERROR "rosbag info failed or is wrong (${rc}): ${info}${se}")
endif()
execute_process(COMMAND /usr/bin/python3 ${CMAKE_CURRENT_LIST_DIR}/read_filtered_bag.py ${out}
                RESULT_VARIABLE rc OUTPUT_VARIABLE so ERROR_VARIABLE se)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "python3-rosbag could not read the bag (${rc}): ${so}${se}")
endif()
file(REMOVE ${out})
message(STATUS "rosbag info and python3-rosbag read the bag: ${so}")
