! Reads a NASA Ames Mars GCM dust file pair with the model's own read statements and prints
! what it read, one number a line (es24.16): per radius qextv, qscatv, gv, then qexti, qscati, gi.
!
! The loop is the dust part of the 15-band branch of ames_radsetup in
! atmos_param_mars/Rad/rtmod_mgcm.F90, nasa/AmesGCM commit
! eaba9b5400031651f6d5545acbca08eaf471defb (lines 4826-4833): its READ statements as they
! stand, with nbin_rt = 20, nlonv = L_NSPECTV = 7 and nloni = L_NSPECTI = 8 as set there
! (the arrays are real*4 there too).
program ames_read
  implicit none
  integer, parameter :: nbin_rt = 20, nlonv = 7, nloni = 8
  real*4, dimension(nbin_rt,nlonv) :: qextv_dst, qscatv_dst, gv_dst
  real*4, dimension(nbin_rt,nloni) :: qexti_dst, qscati_dst, gi_dst
  character(len=512) :: vis, ir
  integer :: i, l

  call get_command_argument(1, vis)
  call get_command_argument(2, ir)
  open(62,file=trim(vis))
  open(63,file=trim(ir))

  do i = 1, nbin_rt
      read(62,'(7(e10.3,2x))') (qextv_dst(i,l), l=1,nlonv)
      read(62,'(7(e10.3,2x))') (qscatv_dst(i,l), l=1,nlonv)
      read(62,'(7(e10.3,2x))') (gv_dst(i,l), l=1,nlonv)
      read(63,'(8(e10.3,2x))') (qexti_dst(i,l), l=1,nloni)
      read(63,'(8(e10.3,2x))') (qscati_dst(i,l), l=1,nloni)
      read(63,'(8(e10.3,2x))') (gi_dst(i,l), l=1,nloni)
  enddo
  close(62)
  close(63)

  do i = 1, nbin_rt
    print '(es24.16)', qextv_dst(i,:), qscatv_dst(i,:), gv_dst(i,:)
  enddo
  do i = 1, nbin_rt
    print '(es24.16)', qexti_dst(i,:), qscati_dst(i,:), gi_dst(i,:)
  enddo
end program ames_read
