/** \file register.cpp
 * Registers every keygrid map class with MRPT's RTTI when libkeygrid_maps.so is loaded, so
 * that deserialization (CArchive >>), CMultiMetricMap INI creation and the MRPT tools that
 * load plugins (SceneViewer3D -l, RawLogViewer -l, rawlog-edit -p) know the classes.
 * One registerClass line per class.
 */
#include <keygrid/maps/CHOCPointsMap.h>
#include <keygrid/maps/CISMOccupancyGrid2D.h>
#include <keygrid/maps/CSubmappedOccupancyGrid3D.h>
#include <mrpt/core/initializer.h>
#include <mrpt/rtti/CObject.h>

MRPT_INITIALIZER(keygrid_maps_registerAllClasses)
{
	mrpt::rtti::registerClass(CLASS_ID(keygrid::CHOCPointsMap));
	mrpt::rtti::registerClass(CLASS_ID(keygrid::CISMOccupancyGrid2D));
	mrpt::rtti::registerClass(CLASS_ID(keygrid::CSubmappedOccupancyGrid3D));
}
