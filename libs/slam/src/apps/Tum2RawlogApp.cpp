#include <keygrid/core/CommandLine.h>
#include <keygrid/core/ProgressBar.h>
#include <keygrid/core/RawlogWriter.h>
#include <keygrid/core/RgbdObservation.h>
#include <keygrid/core/TumFrameSource.h>
#include <keygrid/slam/apps/AppRunner.h>
#include <keygrid/slam/apps/Tum2RawlogApp.h>

#include <cstdio>
#include <iostream>

namespace keygrid::slam
{
std::size_t convertTumToRawlog(const Tum2RawlogOptions& o)
{
	core::FrameSourceOptions so;
	so.maxAssociationDt = o.maxAssociationDt;
	if (!o.camera.empty()) so.camera = core::RgbdCamera::FromPresetOrFile(o.camera);
	core::TumFrameSource src(o.input, so);
	if (!o.quiet)
	{
		std::cerr << "keygrid-tum2rawlog: " << src.describe() << "\n";
		for (const auto& is : src.sequence().issues()) std::cerr << "  skipped line " << is.str() << "\n";
	}
	core::RawlogWriterOptions wo;
	wo.externalImages = o.externalImages;
	core::RawlogWriter writer(o.output, wo);
	const std::size_t n = src.sequence().pairs().size();
	core::ProgressBar bar("converting", n, !o.quiet);
	core::Frame f;
	for (std::size_t i = 0; i < n; i++)
	{
		src.loadFrame(i, f);
		writer.write(core::makeRgbdObservation(f));
		bar.update(i + 1);
	}
	writer.close();
	bar.finish();
	return writer.count();
}

int Tum2RawlogApp::run(int argc, const char* const* argv)
{
	return runApp("keygrid-tum2rawlog", [&] {
		core::CommandLine cl(
			"keygrid-tum2rawlog",
			"Converts a TUM RGB-D folder (rgb/, depth/, associations.txt or rgb.txt+depth.txt) into an\n"
			"MRPT rawlog of CObservation3DRangeScan observations (colour image + depth at rangeUnits\n"
			"= 1/5000 m, no precision lost), readable by rawlog-edit, RawLogViewer and keygrid-slam.");
		cl.option("input", "TUM_DIR", "TUM RGB-D sequence folder", true)
			.option("output", "OUT.rawlog", "rawlog to write (written atomically)", true)
			.option(
				"camera", "fr1|fr2|fr3|icl|kinect|FILE.ini",
				"camera preset, or an INI file with a [camera] section", false,
				"from DIR/camera.ini or the folder name, else kinect")
			.option("max-dt", "SECONDS", "largest |t_rgb - t_depth| when associating rgb.txt/depth.txt", false, "0.02")
			.flag("external-images", "store colour images as PNG files in OUT_Images/ (rawlog-grabber layout)")
			.flag("quiet", "no progress output");
		if (!cl.parse(argc, argv)) return 0;
		Tum2RawlogOptions o;
		o.input = cl.get("input");
		o.output = cl.get("output");
		if (cl.has("camera")) o.camera = cl.get("camera");
		o.maxAssociationDt = cl.getDouble("max-dt");
		if (!(o.maxAssociationDt > 0)) throw core::CommandLineError("--max-dt must be > 0");
		o.externalImages = cl.flagSet("external-images");
		o.quiet = cl.flagSet("quiet");
		const std::size_t n = convertTumToRawlog(o);
		std::cout << "wrote " << n << " CObservation3DRangeScan observations to " << o.output << "\n";
		return 0;
	});
}

}  // namespace keygrid::slam
