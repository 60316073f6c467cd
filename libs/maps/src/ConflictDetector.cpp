#include "detail/Grid3DConfig.h"
#include "detail/Grid3DParallel.h"

#include <keygrid/maps/ConflictDetector.h>
#include <mrpt/config/CConfigFileBase.h>

#include <cmath>

namespace keygrid
{
void ConflictOptions::loadFromConfigFile(
	const mrpt::config::CConfigFileBase& c, const std::string& s)
{
	using detail::readNumber;
	travelledDistanceThreshold =
		readNumber(c, s, "travelledDistanceThreshold", travelledDistanceThreshold);
	occupiedConfidentLogOdds =
		static_cast<float>(readNumber(c, s, "occupiedConfidentLogOdds", occupiedConfidentLogOdds));
	freeConfidentLogOdds =
		static_cast<float>(readNumber(c, s, "freeConfidentLogOdds", freeConfidentLogOdds));
	conflictMinVoxels = readNumber(c, s, "conflictMinVoxels", conflictMinVoxels);
	conflictMinFraction = readNumber(c, s, "conflictMinFraction", conflictMinFraction);
	localizationEnterHitFraction =
		readNumber(c, s, "localizationEnterHitFraction", localizationEnterHitFraction);
	localizationExitHitFraction =
		readNumber(c, s, "localizationExitHitFraction", localizationExitHitFraction);
	localizationMaxContradictionFraction = readNumber(
		c, s, "localizationMaxContradictionFraction", localizationMaxContradictionFraction);
	validate();
}

void ConflictOptions::saveToConfigFile(
	mrpt::config::CConfigFileBase& c, const std::string& s) const
{
	detail::writeNumber(c, s, "travelledDistanceThreshold", travelledDistanceThreshold);
	detail::writeNumber(c, s, "occupiedConfidentLogOdds", occupiedConfidentLogOdds);
	detail::writeNumber(c, s, "freeConfidentLogOdds", freeConfidentLogOdds);
	detail::writeNumber(c, s, "conflictMinVoxels", conflictMinVoxels);
	detail::writeNumber(c, s, "conflictMinFraction", conflictMinFraction);
	detail::writeNumber(c, s, "localizationEnterHitFraction", localizationEnterHitFraction);
	detail::writeNumber(c, s, "localizationExitHitFraction", localizationExitHitFraction);
	detail::writeNumber(c, s, "localizationMaxContradictionFraction", localizationMaxContradictionFraction);
}

void ConflictOptions::validate() const
{
	using detail::require;
	require(travelledDistanceThreshold > 0, "travelledDistanceThreshold",
		travelledDistanceThreshold, "> 0 m");
	require(occupiedConfidentLogOdds > 0, "occupiedConfidentLogOdds", occupiedConfidentLogOdds,
		"> 0");
	require(freeConfidentLogOdds < 0, "freeConfidentLogOdds", freeConfidentLogOdds, "< 0");
	require(conflictMinVoxels >= 1, "conflictMinVoxels", conflictMinVoxels, ">= 1");
	require(conflictMinFraction >= 0 && conflictMinFraction <= 1, "conflictMinFraction",
		conflictMinFraction, "in [0, 1]");
	require(localizationEnterHitFraction > 0 && localizationEnterHitFraction <= 1,
		"localizationEnterHitFraction", localizationEnterHitFraction, "in (0, 1]");
	require(localizationExitHitFraction >= 0 && localizationExitHitFraction <= 1,
		"localizationExitHitFraction", localizationExitHitFraction, "in [0, 1]");
	require(localizationMaxContradictionFraction >= 0 &&
			localizationMaxContradictionFraction <= 1,
		"localizationMaxContradictionFraction", localizationMaxContradictionFraction,
		"in [0, 1]");
}

FrameEvidence evaluateFrame(
	const VoxelBlockGrid& grid, const FrameVoxelUpdates& upd, double travelled,
	const ConflictOptions& opts, unsigned threads)
{
	const unsigned nt = detail::resolveThreads(threads);
	std::vector<FrameEvidence> partial(nt);
	detail::parallelChunks(upd.chunks.size(), nt, [&](std::size_t b, std::size_t e, unsigned t) {
		FrameEvidence ev;
		for (std::size_t i = b; i < e; ++i)
		{
			const auto& ch = upd.chunks[i];
			const VoxelBlock* blk = grid.findBlock(ch.block);
			for (int k = 0; k < VoxelBlock::kVoxels; ++k)
			{
				const uint8_t m = ch.marks[k];
				if (!m) continue;
				const bool hit = FrameVoxelUpdates::isHit(m);
				++ev.updated;
				ev.hits += hit ? 1 : 0;
				if (!blk) continue;
				const Voxel& v = blk->voxels[k];
				if (!v.isKnown()) continue;
				++ev.known;
				const bool contradicts = (!hit && v.logOdds >= opts.occupiedConfidentLogOdds) ||
					(hit && v.logOdds <= opts.freeConfidentLogOdds);
				const bool stale =
					std::abs(travelled - double(v.travelled)) > opts.travelledDistanceThreshold;
				if (hit && v.logOdds > 0.0f)
				{
					++ev.hitsOnOccupied;
					ev.hitsOnStaleOccupied += stale ? 1 : 0;
				}
				ev.contradictions += contradicts ? 1 : 0;
				ev.stale += stale ? 1 : 0;
				ev.staleContradictions += (stale && contradicts) ? 1 : 0;
			}
		}
		partial[t] = ev;
	}, 512);
	FrameEvidence sum;
	for (const auto& p : partial)
	{
		sum.updated += p.updated;
		sum.hits += p.hits;
		sum.known += p.known;
		sum.hitsOnOccupied += p.hitsOnOccupied;
		sum.hitsOnStaleOccupied += p.hitsOnStaleOccupied;
		sum.contradictions += p.contradictions;
		sum.stale += p.stale;
		sum.staleContradictions += p.staleContradictions;
	}
	return sum;
}

const char* toString(MappingMode m)
{
	return m == MappingMode::Localization ? "localization" : "exploration";
}

MappingModeMachine::Decision MappingModeMachine::step(const FrameEvidence& ev)
{
	Decision d;
	const bool revisit = m_pendingRevisit;
	m_pendingRevisit = false;
	if (revisit)
	{
		m_mode = MappingMode::Localization;
		d.reason = "loop closure / relocalization";
	}
	else if (m_mode == MappingMode::Exploration)
	{
		if (ev.revisitHitFraction() >= m_opts.localizationEnterHitFraction &&
			ev.staleContradictionFraction() <= m_opts.localizationMaxContradictionFraction)
		{
			m_mode = MappingMode::Localization;
			d.reason = "hits land consistently on voxels mapped long ago";
		}
	}
	else if (ev.occupiedHitFraction() < m_opts.localizationExitHitFraction)
	{
		m_mode = MappingMode::Exploration;
		d.reason = "hits leave the mapped space";
	}

	if (m_mode == MappingMode::Exploration &&
		double(ev.staleContradictions) >= m_opts.conflictMinVoxels &&
		ev.staleContradictionFraction() >= m_opts.conflictMinFraction)
	{
		d.conflict = true;
		d.reason = std::to_string(ev.staleContradictions) +
			" stale voxels contradicted during exploration";
	}
	d.mode = m_mode;
	return d;
}

}  // namespace keygrid
