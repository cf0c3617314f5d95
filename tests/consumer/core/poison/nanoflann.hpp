#error "knnocc::core must compile without nanoflann and Eigen, but this header was included"
