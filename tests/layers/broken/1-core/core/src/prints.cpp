// A core file that prints and reads a bag: the layer check must refuse it.
#include <rosbag/bag.h>

#include <iostream>
