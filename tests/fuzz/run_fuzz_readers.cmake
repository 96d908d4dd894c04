# Writes a seed corpus (one small file of each format the readers know, plus the real
# centerlines of the shared data folder when present) and runs the reader fuzzer on it.
# Leak detection is off: VTK's XML reader leaks a few objects on some malformed files.
# Usage: cmake -DFUZZER=... -DWORK_DIR=... [-DSHARED_DIR=...] [-DSECONDS=60] -P run_fuzz_readers.cmake
if(NOT SECONDS)
  set(SECONDS 60)
endif()
set(corpus ${WORK_DIR}/corpus)
file(REMOVE_RECURSE ${WORK_DIR})
file(MAKE_DIRECTORY ${corpus} ${WORK_DIR}/artifacts)

file(WRITE ${corpus}/vmtk.vtp [=[<?xml version="1.0"?>
<VTKFile type="PolyData" version="0.1" byte_order="LittleEndian">
<PolyData>
<Piece NumberOfPoints="7" NumberOfVerts="0" NumberOfLines="2" NumberOfStrips="0" NumberOfPolys="0">
<PointData>
<DataArray type="Float64" Name="MaximumInscribedSphereRadius" NumberOfComponents="1" format="ascii">3 3 2 2 3 3 1.5</DataArray>
</PointData>
<CellData>
</CellData>
<Points>
<DataArray type="Float64" NumberOfComponents="3" format="ascii">0 0 0 0 0 -5 2 0 -9 4 0 -12 0 0 0 0 0 -5 -3 0 -10</DataArray>
</Points>
<Lines>
<DataArray type="Int64" Name="connectivity" format="ascii">0 1 2 3 4 5 6</DataArray>
<DataArray type="Int64" Name="offsets" format="ascii">4 7</DataArray>
</Lines>
</Piece>
</PolyData>
</VTKFile>
]=])

file(WRITE ${corpus}/split.vtp [=[<?xml version="1.0"?>
<VTKFile type="PolyData" version="0.1" byte_order="LittleEndian">
<PolyData>
<Piece NumberOfPoints="8" NumberOfVerts="0" NumberOfLines="4" NumberOfStrips="0" NumberOfPolys="0">
<PointData>
<DataArray type="Float64" Name="MaximumInscribedSphereRadius" NumberOfComponents="1" format="ascii">3 3 2 2 3 3 2 2</DataArray>
</PointData>
<CellData>
<DataArray type="Int32" Name="CenterlineIds" NumberOfComponents="1" format="ascii">0 0 1 1</DataArray>
<DataArray type="Int32" Name="TractIds" NumberOfComponents="1" format="ascii">0 1 0 1</DataArray>
<DataArray type="Int32" Name="Blanking" NumberOfComponents="1" format="ascii">0 0 0 0</DataArray>
<DataArray type="Int32" Name="GroupIds" NumberOfComponents="1" format="ascii">0 1 0 2</DataArray>
</CellData>
<Points>
<DataArray type="Float64" NumberOfComponents="3" format="ascii">0 0 0 0 0 -5 0 0 -5 3 0 -9 0 0 0 0 0 -5 0 0 -5 -3 0 -9</DataArray>
</Points>
<Lines>
<DataArray type="Int64" Name="connectivity" format="ascii">0 1 2 3 4 5 6 7</DataArray>
<DataArray type="Int64" Name="offsets" format="ascii">2 4 6 8</DataArray>
</Lines>
</Piece>
</PolyData>
</VTKFile>
]=])

file(WRITE ${corpus}/rom.vtp [=[<?xml version="1.0"?>
<VTKFile type="PolyData" version="0.1" byte_order="LittleEndian">
<PolyData>
<Piece NumberOfPoints="6" NumberOfVerts="0" NumberOfLines="5" NumberOfStrips="0" NumberOfPolys="0">
<PointData>
<DataArray type="Int64" Name="BranchId" NumberOfComponents="1" format="ascii">0 0 -1 1 2 2</DataArray>
<DataArray type="Int64" Name="BifurcationId" NumberOfComponents="1" format="ascii">-1 -1 0 -1 -1 -1</DataArray>
<DataArray type="Float64" Name="Path" NumberOfComponents="1" format="ascii">0 1 0 1 1 2</DataArray>
<DataArray type="Float64" Name="CenterlineSectionArea" NumberOfComponents="1" format="ascii">3 3 2 1 1 1</DataArray>
</PointData>
<Points>
<DataArray type="Float64" NumberOfComponents="3" format="ascii">0 0 0 0 0 -1 0 0 -2 1 0 -3 -1 0 -3 -2 0 -4</DataArray>
</Points>
<Lines>
<DataArray type="Int64" Name="connectivity" format="ascii">0 1 1 2 2 3 2 4 4 5</DataArray>
<DataArray type="Int64" Name="offsets" format="ascii">2 4 6 8 10</DataArray>
</Lines>
</Piece>
</PolyData>
</VTKFile>
]=])

file(WRITE ${corpus}/tree.vtk [=[# vtk DataFile Version 3.0
vtk output
ASCII
DATASET POLYDATA
POINTS 5 float
0 0 0 1 0 0 2 0 0 3 1 0 3 -1 0
LINES 3 10
3 0 1 2
2 2 3
2 2 4
POINT_DATA 5
SCALARS radii double
LOOKUP_TABLE default
1 1 0.8 0.5 0.6
]=])

file(WRITE ${corpus}/network.yaml [=[length_unit: mm
branches:
  - name: trunk
    points: [[0, 0, 0, 5], [0, 0, -40, 5]]
  - name: left
    points: [[0, 0, -40, 3], [-10, 0, -60, 3]]
  - name: right
    points: [[0, 0, -40, 3], [10, 0, -60, 2]]
]=])

file(WRITE ${corpus}/exact.yaml [=[length_unit: m
branches:
  - name: a
    points: [[0, 0, 0, 0.01], [0.01, 0, 0, 0.01]]
    nodes: [0, 1]
    segments: [0]
nodes:
  - [0, 0, 0]
  - [0.01, 0, 0]
segments:
  - [0, 1, 0.01, 0.01, 0]
]=])

file(WRITE ${corpus}/deck.in [=[MODEL test_
NODE 0 0.0 0.0 0.0
NODE 1 0.0 0.0 -2.0
NODE 2 0.0 0.0 -5.0
NODE 5 0.3 0.0 -2.0
NODE 6 2.0 0.0 -4.0
SEGMENT main_0 0 2.0 10 0 1 1.0 0.8 0.0 MAT1 NONE 0.0 0 0 NOBOUND NONE
SEGMENT main_1 1 3.0 10 1 2 0.8 0.5 0.0 MAT1 NONE 0.0 0 0 RESISTANCE R1
SEGMENT side_0 2 2.7 10 5 6 0.2 0.1 0.0 MAT1 NONE 0.0 0 0 RESISTANCE R2
JOINT J1 5 IN1 OUT1
JOINTINLET IN1 1 0
JOINTOUTLET OUT1 2 1 2
DATATABLE R1 LIST
0.0 100.0
ENDDATATABLE
]=])

if(SHARED_DIR AND EXISTS ${SHARED_DIR}/data/real)
  file(GLOB_RECURSE real_files ${SHARED_DIR}/data/real/*centerline*.vtp ${SHARED_DIR}/data/real/*.vtk
       ${SHARED_DIR}/data/real/*.in)
  foreach(f ${real_files})
    get_filename_component(name ${f} NAME)
    file(SIZE ${f} size)
    if(size LESS 60000)
      configure_file(${f} ${corpus}/real_${name} COPYONLY)
    endif()
  endforeach()
endif()

execute_process(
  COMMAND ${CMAKE_COMMAND} -E env ASAN_OPTIONS=detect_leaks=0 ${FUZZER} ${corpus} -max_total_time=${SECONDS} -max_len=8192 -timeout=20 -rss_limit_mb=3072 -detect_leaks=0
          -artifact_prefix=${WORK_DIR}/artifacts/ -print_final_stats=1
  WORKING_DIRECTORY ${WORK_DIR}
  RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "fuzz_readers found a problem (exit ${rc}); reproducer in ${WORK_DIR}/artifacts")
endif()
