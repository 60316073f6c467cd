#pragma once
/** \file VocabApp.h
 * keygrid-vocab: trains a vocabulary tree (keygrid::loop::Vocabulary) on images, a rawlog or a
 * TUM folder (`train`), and describes a vocabulary file (`info`).
 */
namespace keygrid::slam
{
class VocabApp
{
   public:
	int run(int argc, const char* const* argv);
};

}  // namespace keygrid::slam
