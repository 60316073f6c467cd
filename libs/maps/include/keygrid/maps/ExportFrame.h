#pragma once
/** \file ExportFrame.h
 * The frame a map file is written in (keygrid-slam: the run's floor frame), and the line of
 * metadata that records it in the file (a PLY `comment`, a comment line of an OctoMap .bt
 * header).
 */
#include <mrpt/poses/CPose3D.h>

#include <optional>
#include <string>

namespace keygrid::maps
{
struct ExportFrame
{
	/** Points are written as T_out_world * p_world (Default: identity, the map's own frame) */
	mrpt::poses::CPose3D T_out_world;
	/** Metadata line without its comment marker, e.g. "keygrid T_world_floor (x y z qx qy qz
	 * qw): ..."; empty = none (Default: empty) */
	std::string comment;

	bool isIdentity() const
	{
		return T_out_world.translation().norm() == 0 && T_out_world.getRotationMatrix() == mrpt::math::CMatrixDouble33::Identity();
	}
};

/** "keygrid T_world_floor (x y z qx qy qz qw): x y z qx qy qz qw" (%.9g), the metadata line
 * of every map output in the floor frame (the same as map_2d.yaml's first-line comment). */
std::string floorFrameComment(const mrpt::poses::CPose3D& T_world_floor);
/** The pose of a floorFrameComment() line, read back from a file's metadata line with or
 * without its comment marker ("# keygrid T_world_floor ...", "comment keygrid ..."); nullopt
 * when the line is not one or its seven numbers are missing. */
std::optional<mrpt::poses::CPose3D> floorFrameFromComment(const std::string& line);

/** A pose as the 12 numbers of its 3x4 matrix [R | t], row by row, with 17 significant digits:
 * poseFromMatrixText() gives back the same rotation matrix and translation bit for bit (yaw,
 * pitch, roll text would not: near roll = +-180 deg it may flip the quaternion's sign). */
std::string poseMatrixText(const mrpt::poses::CPose3D& p);
/** The pose of poseMatrixText(); throws std::invalid_argument on text that is not 12 numbers. */
mrpt::poses::CPose3D poseFromMatrixText(const std::string& text);

/** The floor frame as an ExportFrame: T_out_world = inverse(T_world_floor), with its comment. */
ExportFrame floorExportFrame(const mrpt::poses::CPose3D& T_world_floor);

}  // namespace keygrid::maps
