import glob
import os

from setuptools import find_packages, setup

package_name = 'hrc_common'

setup(
    name=package_name,
    version='0.1.0',
    packages=find_packages(exclude=['test']),
    data_files=[
        ('share/ament_index/resource_index/packages', ['resource/' + package_name]),
        ('share/' + package_name, ['package.xml']),
        # every parameter and data file: hrc_common.paths.params_dir() of an installation
        ('share/' + package_name + '/params',
         glob.glob(os.path.join('..', '..', 'params', '*.yaml'))),
        # the learning configurations (hrc session --learning NAME)
        ('share/' + package_name + '/params/learning',
         glob.glob(os.path.join('..', '..', 'params', 'learning', '*.yaml'))),
    ],
    install_requires=['setuptools'],
    zip_safe=True,
    maintainer='hrc developers',
    maintainer_email='hrc@example.org',
    description='Shared pieces of the hrc nodes.',
    license='Apache-2.0',
    entry_points={'console_scripts': []},
)
