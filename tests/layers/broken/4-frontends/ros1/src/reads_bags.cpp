// A node that reads bags and runs a job: the layer check must refuse it.
#include "dispel/io/ros1_bag.hpp"
#include "dispel/jobs/filter_job.hpp"
