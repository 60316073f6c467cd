#pragma once
/** \file ConflictDetector.h
 * Exploration vs localization (the paper's Fig. 1a) and travelled-distance conflicts.
 *
 * Every voxel remembers the travelled distance s_v of the camera that last updated it. When a
 * frame with camera travelled distance s would update a known voxel with |s - s_v| > threshold,
 * the voxel was mapped "long ago" along the trajectory; if the new evidence also contradicts it
 * (a confidently occupied voxel would be carved free, or a confidently free voxel would be hit),
 * it is a *stale contradiction*. In exploration, many stale contradictions mean that the
 * accumulated drift would destroy the grid: a conflict, answered by opening a new submap.
 *
 * The mode machine:
 *   Exploration  -> Localization : a loop-closure / relocalization event, or the frame's hits
 *                                  land mostly on occupied voxels mapped long ago along the
 *                                  trajectory (stale: share >= localizationEnterHitFraction)
 *                                  with few stale contradictions (share of the hits <=
 *                                  localizationMaxContradictionFraction): a consistent revisit.
 *                                  (Hits on recently mapped voxels do not count: consecutive
 *                                  frames always overlap.)
 *   Localization -> Exploration  : no event and the share of hits on occupied voxels of any age
 *                                  drops below localizationExitHitFraction (the camera leaves
 *                                  the mapped space; the first revisit frame refreshes the old
 *                                  voxels, so staleness cannot be the criterion to stay)
 *   conflict                     : only in Exploration, when the stale contradictions reach both
 *                                  conflictMinVoxels and conflictMinFraction of the frame's hit voxels.
 */
#include <keygrid/core/FieldTableOptions.h>
#include <keygrid/core/OptionFields.h>
#include <keygrid/maps/DepthFrameIntegrator.h>
#include <keygrid/maps/VoxelBlockGrid.h>

#include <cstddef>
#include <string>

namespace keygrid
{
/** Parameters of the mode machine and of conflict detection. */
struct ConflictOptions : public core::FieldTableOptions<ConflictOptions>
{
	/** |camera travelled - voxel travelled| above which a known voxel is "stale" [m]
	 * (Default: 1.5 m) */
	double travelledDistanceThreshold{1.5};
	/** A voxel with log-odds >= this is confidently occupied (Default: 1.5, p = 0.82) */
	float occupiedConfidentLogOdds{1.5f};
	/** A voxel with log-odds <= this is confidently free (Default: -1.5, p = 0.18) */
	float freeConfidentLogOdds{-1.5f};
	/** Stale contradictions needed for a conflict [voxels] (Default: 300) */
	double conflictMinVoxels{300};
	/** ... and as a share of the frame's hit voxels (Default: 0.05) */
	double conflictMinFraction{0.05};
	/** Share of the hits on stale occupied voxels (a revisit) to enter localization
	 * (Default: 0.2) */
	double localizationEnterHitFraction{0.2};
	/** Share of the hits on occupied voxels (any age) below which localization ends
	 * (Default: 0.25) */
	double localizationExitHitFraction{0.25};
	/** Largest stale-contradiction share (of the hits) that still counts as a consistent
	 * revisit when entering localization from occupancy alone (Default: 0.02) */
	double localizationMaxContradictionFraction{0.02};

	/** The INI keys, with description and rule. */
	core::OptionFields fields();
	/** Throws std::invalid_argument naming [section], key and value of the first bad field. */
	void validate(const std::string& section = "insertOpts") const;
};

/** What one frame would do to a grid, counted before it is applied. */
struct FrameEvidence
{
	std::size_t updated{0};  //!< voxels the frame updates
	std::size_t hits{0};  //!< of which hits
	std::size_t known{0};  //!< updated voxels that were already known
	std::size_t hitsOnOccupied{0};  //!< hits on voxels already occupied (log-odds > 0)
	std::size_t hitsOnStaleOccupied{0};  //!< of which the voxel is stale (mapped long ago)
	std::size_t contradictions{0};  //!< known voxels whose confident state would be reversed
	std::size_t stale{0};  //!< known voxels with |travelled difference| > threshold
	std::size_t staleContradictions{0};  //!< stale and contradicted

	double occupiedHitFraction() const { return hits ? double(hitsOnOccupied) / double(hits) : 0.0; }
	/** Share of the hits on occupied voxels mapped long ago: how much of the frame revisits. */
	double revisitHitFraction() const
	{
		return hits ? double(hitsOnStaleOccupied) / double(hits) : 0.0;
	}
	double contradictionFraction() const
	{
		return known ? double(contradictions) / double(known) : 0.0;
	}
	/** Stale contradictions per hit voxel of the frame (how much of the observed surface
	 * disagrees with old map content). */
	double staleContradictionFraction() const
	{
		return hits ? double(staleContradictions) / double(hits) : 0.0;
	}
};

/** Counts FrameEvidence of `upd` against `grid` for a camera that travelled `travelled` m.
 * Uses `threads` workers (0 = all); the counts do not depend on the thread count. */
FrameEvidence evaluateFrame(
	const VoxelBlockGrid& grid, const FrameVoxelUpdates& upd, double travelled,
	const ConflictOptions& opts, unsigned threads = 0);

enum class MappingMode : uint8_t
{
	Exploration = 0,
	Localization = 1
};
const char* toString(MappingMode m);

/** The exploration / localization state machine. */
class MappingModeMachine
{
   public:
	struct Decision
	{
		MappingMode mode{MappingMode::Exploration};  //!< mode after this frame
		bool conflict{false};  //!< open a new submap before applying the frame
		std::string reason;  //!< human-readable cause of the transition / conflict
	};

	explicit MappingModeMachine(const ConflictOptions& opts = {}) : m_opts(opts) {}
	void setOptions(const ConflictOptions& opts) { m_opts = opts; }

	MappingMode mode() const { return m_mode; }
	void setMode(MappingMode m) { m_mode = m; }
	/** A loop closure or relocalization was detected: the next frame is in localization. */
	void notifyRevisit() { m_pendingRevisit = true; }
	bool revisitPending() const { return m_pendingRevisit; }

	/** Advances the machine with one frame's evidence (consumes a pending revisit event). */
	Decision step(const FrameEvidence& ev);

   private:
	ConflictOptions m_opts;
	MappingMode m_mode{MappingMode::Exploration};
	bool m_pendingRevisit{false};
};

}  // namespace keygrid
