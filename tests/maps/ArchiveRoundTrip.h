#pragma once
/** \file ArchiveRoundTrip.h
 * A map written to an MRPT archive in memory and read back into a fresh object of its class.
 */
#include <mrpt/io/CMemoryStream.h>
#include <mrpt/serialization/CArchive.h>

namespace keygrid::test
{
template <class Map>
Map archiveRoundTrip(const Map& map)
{
	mrpt::io::CMemoryStream buf;
	auto arch = mrpt::serialization::archiveFrom(buf);
	arch << map;
	buf.Seek(0);
	Map back;
	arch >> back;
	return back;
}

}  // namespace keygrid::test
