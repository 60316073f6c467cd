#include "detail/Grid3DParallel.h"
#include "detail/OptionValues.h"

#include <keygrid/maps/ConflictDetector.h>
#include <mrpt/config/CConfigFileBase.h>

#include <cmath>

namespace keygrid
{
core::OptionFields ConflictOptions::fields()
{
	using R = core::OptionRule;
	core::OptionFields f;
	f.add("travelledDistanceThreshold", travelledDistanceThreshold, "a known voxel is stale when the camera travelled more than this since it was last updated [m]", R::positive());
	f.add("occupiedConfidentLogOdds", occupiedConfidentLogOdds, "a voxel with log-odds >= this is confidently occupied (a miss contradicts it)", R::positive());
	f.add("freeConfidentLogOdds", freeConfidentLogOdds, "a voxel with log-odds <= this is confidently free (a hit contradicts it)", detail::negative());
	f.add("conflictMinVoxels", conflictMinVoxels, "exploration: stale contradicted voxels of a frame that open a new submap [voxels] ...", R::atLeast(1));
	f.add("conflictMinFraction", conflictMinFraction, "... and their least share of the frame's hit voxels", R::inRange(0, 1));
	f.add("localizationEnterHitFraction", localizationEnterHitFraction, "share of a frame's hits on stale occupied voxels (a revisit) that enters localization", R::aboveUpTo(0, 1));
	f.add("localizationExitHitFraction", localizationExitHitFraction, "localization ends when the share of hits on occupied voxels falls below this", R::inRange(0, 1));
	f.add("localizationMaxContradictionFraction", localizationMaxContradictionFraction, "a revisit enters localization only with at most this share of stale contradictions (of the hits)", R::inRange(0, 1));
	return f;
}

void ConflictOptions::validate(const std::string& s) const { core::validateFields(*this, s); }

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
