# Finds Debian's ROS 1 message headers and bag library and makes two imported targets:
#  - Ros1::messages: the message headers (sensor_msgs, nav_msgs, geometry_msgs, tf2_msgs) and
#    rostime; what converting ROS 1 messages needs (a live node uses no more).
#  - RosBag::storage: the bag library (librosbag-storage-dev) on top of it.
# Debian's rosbag_storage.pc is broken (it requires pluginlib, which has no .pc file), so the
# libraries are linked directly and the include directories of pluginlib, class_loader, rcutils,
# rcpputils and ament_index_cpp are added by hand.
find_path(RosBagStorage_INCLUDE_DIR rosbag/bag.h)
find_path(RosBagStorage_ROSTIME_DIR ros/time.h)
find_path(RosBagStorage_PLUGINLIB_DIR pluginlib/class_loader.hpp PATH_SUFFIXES pluginlib)
find_path(RosBagStorage_CLASS_LOADER_DIR class_loader/class_loader.hpp PATH_SUFFIXES class_loader)
find_path(RosBagStorage_SENSOR_MSGS_DIR sensor_msgs/LaserScan.h)
find_path(RosBagStorage_TF2_MSGS_DIR tf2_msgs/TFMessage.h)
find_path(RosBagStorage_NAV_MSGS_DIR nav_msgs/Odometry.h)
foreach(lib rostime cpp_common)
  find_library(RosBagStorage_${lib}_LIBRARY ${lib})
  list(APPEND Ros1Messages_LIBRARIES ${RosBagStorage_${lib}_LIBRARY})
  list(APPEND _rosbag_lib_vars RosBagStorage_${lib}_LIBRARY)
endforeach()
foreach(lib rosbag_storage roscpp_serialization console_bridge roslz4 bz2 boost_filesystem)
  find_library(RosBagStorage_${lib}_LIBRARY ${lib})
  list(APPEND RosBagStorage_LIBRARIES ${RosBagStorage_${lib}_LIBRARY})
  list(APPEND _rosbag_lib_vars RosBagStorage_${lib}_LIBRARY)
endforeach()

include(FindPackageHandleStandardArgs)
find_package_handle_standard_args(RosBagStorage
  REQUIRED_VARS RosBagStorage_INCLUDE_DIR RosBagStorage_ROSTIME_DIR RosBagStorage_PLUGINLIB_DIR
                RosBagStorage_CLASS_LOADER_DIR RosBagStorage_SENSOR_MSGS_DIR
                RosBagStorage_TF2_MSGS_DIR RosBagStorage_NAV_MSGS_DIR ${_rosbag_lib_vars})

if(RosBagStorage_FOUND AND NOT TARGET Ros1::messages)
  add_library(Ros1::messages INTERFACE IMPORTED GLOBAL)
  # The ROS headers are not ours: SYSTEM, so that our warnings do not apply to them.
  set_target_properties(Ros1::messages PROPERTIES
    INTERFACE_SYSTEM_INCLUDE_DIRECTORIES "${RosBagStorage_ROSTIME_DIR};${RosBagStorage_SENSOR_MSGS_DIR}"
    INTERFACE_INCLUDE_DIRECTORIES "${RosBagStorage_ROSTIME_DIR};${RosBagStorage_SENSOR_MSGS_DIR}"
    INTERFACE_LINK_LIBRARIES "${Ros1Messages_LIBRARIES}")
endif()
if(RosBagStorage_FOUND AND NOT TARGET RosBag::storage)
  add_library(RosBag::storage INTERFACE IMPORTED GLOBAL)
  set(_dirs ${RosBagStorage_INCLUDE_DIR} ${RosBagStorage_PLUGINLIB_DIR}
            ${RosBagStorage_CLASS_LOADER_DIR})
  foreach(extra rcutils rcpputils ament_index_cpp)
    if(EXISTS ${RosBagStorage_INCLUDE_DIR}/${extra})
      list(APPEND _dirs ${RosBagStorage_INCLUDE_DIR}/${extra})
    endif()
  endforeach()
  set_target_properties(RosBag::storage PROPERTIES
    INTERFACE_SYSTEM_INCLUDE_DIRECTORIES "${_dirs}"
    INTERFACE_INCLUDE_DIRECTORIES "${_dirs}"
    INTERFACE_LINK_LIBRARIES "${RosBagStorage_LIBRARIES};Ros1::messages")
endif()
