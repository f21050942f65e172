# Locates OpenCV core, imgproc and imgcodecs (vkmesh uses them for PNG/JPEG I/O and, imgproc, to resample
# colour images onto the depth grid with cv::remap) and wraps them in the imported target vkmesh::opencv.
# imgcodecs itself depends on imgproc, so this adds no package: Debian's libopencv-imgcodecs-dev pulls in
# libopencv-imgproc-dev.
#
# Why not find_package(OpenCV): Debian ships OpenCVConfig.cmake only in the heavy libopencv-dev
# meta-package, not in libopencv-core-dev / libopencv-imgcodecs-dev, so the headers and libraries are
# located directly. This file is used twice: by vkmesh's own CMakeLists.txt and, installed next to
# vkmeshConfig.cmake, by find_package(vkmesh). The exported vkmesh targets name only `vkmesh::opencv`,
# never a library path, so the installed package finds OpenCV again on the consumer's machine instead of
# carrying the build machine's absolute paths.
#
# Sets vkmesh_opencv_FOUND; never fails by itself (the caller decides how to report a miss).
if(TARGET vkmesh::opencv)
  set(vkmesh_opencv_FOUND TRUE)
  return()
endif()

find_path(VKMESH_OPENCV_INCLUDE_DIR opencv2/imgcodecs.hpp PATH_SUFFIXES opencv4
          DOC "directory holding opencv2/imgcodecs.hpp")
find_library(VKMESH_OPENCV_CORE_LIB opencv_core DOC "OpenCV core library")
find_library(VKMESH_OPENCV_IMGCODECS_LIB opencv_imgcodecs DOC "OpenCV imgcodecs library")
find_library(VKMESH_OPENCV_IMGPROC_LIB opencv_imgproc DOC "OpenCV imgproc library")

if(VKMESH_OPENCV_INCLUDE_DIR AND VKMESH_OPENCV_CORE_LIB AND VKMESH_OPENCV_IMGCODECS_LIB AND VKMESH_OPENCV_IMGPROC_LIB)
  set(vkmesh_opencv_FOUND TRUE)
  # Imported, so its include directory is a SYSTEM one for everything that links it (OpenCV's own
  # headers then raise no -Wall -Wextra warnings in vkmesh or in consumers).
  add_library(vkmesh::opencv INTERFACE IMPORTED)
  set_target_properties(vkmesh::opencv PROPERTIES
    INTERFACE_INCLUDE_DIRECTORIES "${VKMESH_OPENCV_INCLUDE_DIR}"
    # imgcodecs first: it depends on core (matters for static linking order).
    INTERFACE_LINK_LIBRARIES "${VKMESH_OPENCV_IMGCODECS_LIB};${VKMESH_OPENCV_IMGPROC_LIB};${VKMESH_OPENCV_CORE_LIB}")
else()
  set(vkmesh_opencv_FOUND FALSE)
  string(CONCAT vkmesh_opencv_MISSING "OpenCV core/imgcodecs not found (include dir: ${VKMESH_OPENCV_INCLUDE_DIR}, "
         "core: ${VKMESH_OPENCV_CORE_LIB}, imgcodecs: ${VKMESH_OPENCV_IMGCODECS_LIB}, imgproc: ${VKMESH_OPENCV_IMGPROC_LIB}); on Debian 12: "
         "apt-get install libopencv-core-dev libopencv-imgcodecs-dev")
endif()
